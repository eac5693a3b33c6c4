"""The model stage: a constrained mechanical system described by coordinates, energies, particles,
constraints and forces.

Each piece of the model is stored twice: as the user wrote it (global coordinates, for display and
reduction) and in *local* form, with its own coordinates replaced by placeholders. Pieces with equal
local forms share one symbolic derivation and one vectorized numeric kernel, so the symbolic work for a
ring of N identical particles does not grow with N.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ConstraintError, ModelError, ModelTypeError
from pfaff.core.keywords import checked_keywords
from pfaff.core.lazy import LazySeq, NumberedNames, concat
from pfaff.core.reals import real_number
from pfaff.core.symbols import (
    as_expr,
    is_coordinate_like,
    is_physics_vector,
    local_q,
    local_qd,
    speed,
    t,
    validate_coordinates,
)
from pfaff.mechanics.contacts import ContactsMixin, ContactSpec
from pfaff.mechanics.elements import ElementsMixin
from pfaff.mechanics.events import EventsMixin, EventSpec
from pfaff.mechanics.family import Family, Ref, check_name, find_ref, index_range, member_index
from pfaff.mechanics.shapes import ShapesMixin
from pfaff.mechanics.smooth import kinks

if TYPE_CHECKING:
    from sympy.physics.vector import Vector

PIECE_KINDS = (
    "particle", "kinetic", "potential", "force", "genforce", "torque", "dissipation",
    "holonomic", "velocity",
)  # fmt: skip


@dataclass(frozen=True)
class Piece:
    """One term of a model, in global and local form.

    Attributes
    ----------
    kind : str
        One of ``particle``, ``kinetic``, ``potential``, ``force``, ``genforce``, ``holonomic``,
        ``velocity``.
    exprs : tuple of Expr
        The expressions as given (global coordinates): mass then position for a particle, force
        components then point components for a force, the single expression otherwise.
    coords : tuple of int
        Global indices of the coordinates the piece involves, ascending; local coordinate ``a`` is
        ``coords[a]``.
    key : tuple
        Hashable local form: ``(kind, dim, local expressions...)``. Equal keys mean equal derivations.
    name : str
        A label for reports.
    template : Template or None
        For a family piece (``over=k``): the index range and, per local coordinate, a global
        index or a family reference.
    """

    kind: str
    exprs: tuple[sp.Expr, ...]
    coords: tuple[int, ...]
    key: tuple
    name: str
    dim: int = 0
    template: Template | None = None

    @property
    def count(self) -> int:
        """Number of instances (1 for an ordinary piece)."""
        return 1 if self.template is None else self.template.count


@dataclass(frozen=True)
class Template:
    """Instances k = lo … hi of a family piece; ``slots[a]`` is local coordinate a."""

    index: sp.Symbol
    lo: int
    hi: int
    slots: tuple[int | Ref, ...]

    @property
    def count(self) -> int:
        """Number of instances."""
        return self.hi - self.lo + 1

    def progression(self, a: int) -> tuple[int, int]:
        """(start, step) of local coordinate a's global index over the instances."""
        s = self.slots[a]
        return (s, 0) if isinstance(s, int) else (s.column(self.lo), s.stride)


def _slot_name(system: SystemSpec, slot: int | Ref) -> str:
    if isinstance(slot, int):
        return str(speed(system._coord(slot)))
    return f"Derivative({slot.family.name}[{slot.stride}*{slot.index} + {slot.shift}], t)"


class SystemSpec(ElementsMixin, EventsMixin, ContactsMixin, ShapesMixin):
    """A constrained mechanical system as data: coordinates, pieces and their local forms.

    This is the model stage: every ``add_*`` method validates its piece when it is added. The
    user's class :class:`pfaff.System` (in :mod:`pfaff.api`, where the parameters are documented)
    adds the methods that call later stages (``equations()``, ``reduce()``, ``work()``).

    Examples
    --------
    >>> import pfaff
    >>> x, y = pfaff.coordinates("x y")
    >>> spec = SystemSpec([x, y], name="point")
    >>> spec.add_holonomic_constraint(x - y, name="diagonal")
    >>> spec.n, spec.constraint_rows()[0]
    (2, ('diagonal',))
    """

    def __init__(
        self, coordinates: object = None, *, name: str = "system", frame: object = None
    ) -> None:
        self.frame = frame
        self._ordinary: tuple = () if coordinates is None else validate_coordinates(coordinates)
        self.families: list[Family] = []
        self.name = name
        self._index = {q: i for i, q in enumerate(self._ordinary)}
        self._speed_index = {speed(q): i for i, q in enumerate(self._ordinary)}
        self.pieces: list[Piece] = []
        self._parameters: set[sp.Symbol] = set()
        self._constraint_keys: dict[tuple, str] = {}
        self._counts: dict[str, int] = dict.fromkeys(PIECE_KINDS, 0)
        self._pending_refs: dict = {}
        self.bodies: list = []  # rigid bodies (add_rigid_body), in order
        self.inputs: list = []  # parameters declared as inputs (add_input)
        self.shapes: list = []  # drawn solids (add_shape), in order
        self.events: list[EventSpec] = []  # add_event, compiled with the model
        self.contacts: list[ContactSpec] = []  # add_unilateral_constraint (derive/contacts)
        self._defaults: dict[str, float] = {}  # set_parameter_defaults

    # ------------------------------------------------------------------ inspection helpers
    @property
    def coordinates(self) -> tuple | LazySeq:
        """All coordinates: the ordinary ones, then each family's members (made on demand)."""
        if not self.families:
            return self._ordinary
        return concat([self._ordinary, *(f.coordinates for f in self.families)])

    @property
    def speeds(self) -> tuple | LazySeq:
        """q̇ of every coordinate, in coordinate order."""
        qs = self.coordinates
        return (
            tuple(map(speed, qs))
            if isinstance(qs, tuple)
            else LazySeq(len(qs), lambda i: speed(qs[i]))
        )

    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return len(self._ordinary) + sum(f.n for f in self.families)

    @checked_keywords
    def add_family(self, name: str, n: int, *, first: int = 0) -> Family:
        """Append an indexed family of n coordinates ``name{first}`` … ``name{first+n-1}``.

        Parameters
        ----------
        name : str
            Base name; member i is the coordinate ``name{i}`` (e.g. ``theta5``).
        n : int
            Number of members.
        first : int, optional
            Index of the first member (default 0).

        Returns
        -------
        Family
            ``fam[i]`` is member i; ``fam[k + c]`` (k a SymPy symbol) is a template reference for
            pieces added with ``over=k`` or ``over=(k, first, last)``.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> s = pfaff.System()
        >>> th = s.add_family("theta", 3)
        >>> k = sp.Symbol("k")
        >>> s.add_particle(1, [sp.cos(th[k]), sp.sin(th[k])], over=k)
        >>> s.equations().mass_matrix
        Matrix([
        [1, 0, 0],
        [0, 1, 0],
        [0, 0, 1]])
        """
        taken = [str(q.func) for q in self._ordinary] + [f.name for f in self.families]
        name, n = check_name(name, n, first, taken)
        fam = Family(name, n, int(first), self.n)
        self.families.append(fam)
        return fam

    def _resolve(self, f: AppliedUndef) -> int | None:
        i = self._index.get(f)
        return member_index(self.families, f) if i is None and self.families else i

    @property
    def parameters(self) -> tuple[sp.Symbol, ...]:
        """The free symbols of the model other than :data:`t`, sorted by name."""
        return tuple(sorted(self._parameters, key=lambda s: s.name))

    @property
    def parameter_defaults(self) -> dict[str, float]:
        """Default values of parameters, by name (:meth:`set_parameter_defaults`), a copy."""
        return dict(self._defaults)

    def set_parameter_defaults(self, values: dict) -> None:
        """Give parameters default values, used by ``compile()`` where no value is given.

        Parameters
        ----------
        values : dict
            Finite real numbers keyed by parameter (Symbol or name); each must be a parameter
            of the system already. A later call adds to (and overrides) earlier ones.

        Examples
        --------
        >>> import pfaff
        >>> s = pfaff.models.pendulum()
        >>> s.set_parameter_defaults({"g": 9.81})
        >>> s.parameter_defaults
        {'g': 9.81}
        >>> model = s.equations().compile({"m": 1, "L": 1})  # g = 9.81 from the default
        >>> round(float(model.accelerations(0.0, [0.5], [0.0])[0][0]), 6)
        -4.703165
        """
        if not isinstance(values, dict):
            raise ModelError(
                f"`values` must be a dict of parameter values; got {type(values).__name__}"
            )
        names = {p.name for p in self._parameters}
        checked = {}
        for key, value in values.items():
            name = key.name if isinstance(key, sp.Symbol) else key
            if not isinstance(name, str) or name not in names:
                raise ModelError(
                    f"`values`: {str(key)[:80]!r} is not a parameter of this system "
                    f"(its parameters: {', '.join(sorted(names)) or 'none'})"
                )
            checked[name] = real_number(value, f"values[{name!r}]", ModelError)
        self._defaults.update(checked)

    @property
    def constraints(self) -> list[Piece]:
        """Holonomic and velocity constraints in the order they were added (one multiplier each)."""
        return [p for p in self.pieces if p.kind in ("holonomic", "velocity")]

    @property
    def n_constraints(self) -> int:
        """Number of constraints m."""
        return self._counts["holonomic"] + self._counts["velocity"]

    def constraint_rows(self) -> tuple[tuple | LazySeq, np.ndarray]:
        """Name and holonomic flag of every constraint row (a family piece has one per k)."""
        names, flags = [], []
        for p in self.constraints:
            if p.template is None:
                names.append((p.name,))
            else:
                lo, label = p.template.lo, p.name
                names.append(NumberedNames([], [(f"{label} ", lo, p.count)]))
            flags.append(np.full(p.count, p.kind == "holonomic"))
        hol = np.concatenate(flags) if flags else np.zeros(0, dtype=bool)
        return concat(names), hol

    def _scan(
        self,
        exprs: tuple[sp.Expr, ...],
        what: str,
        *,
        speeds: bool,
        refs: dict | None = None,
        smooth: bool = True,
    ) -> tuple[int, ...]:
        """Indices of the coordinates the expressions involve; reject foreign functions of time
        (and, for ``smooth`` terms, those the derivation differentiates, kinks of the state).

        Family references (``theta[k]``) are collected into ``refs`` (function -> Ref) when given.
        """
        used: set[int] = set()
        problems: list[str] = kinks(exprs) if smooth else []
        for e in exprs:
            atoms = e.atoms(sp.Derivative, AppliedUndef, sp.Symbol)
            derivs = [a for a in atoms if isinstance(a, sp.Derivative)]
            for d in derivs:
                j = self._speed_index.get(d)
                if j is None and is_coordinate_like(d.expr) and d.args[1:] == ((t, 1),):
                    j = self._resolve(d.expr)
                    if j is None and (ref := self._ref(d.expr, refs, problems)) is not None:
                        j = ref
                if j is not None:
                    if not speeds:
                        problems.append(
                            f"contains the velocity {d}; positions and holonomic constraints "
                            "may depend on q and t only"
                        )
                    if isinstance(j, int):
                        used.add(j)
                elif is_coordinate_like(d.expr) and (
                    self._resolve(d.expr) is not None or find_ref(self.families, d.expr)
                ):
                    problems.append(f"contains the higher derivative {d}, which is not allowed")
                else:
                    problems.append(
                        f"contains the derivative {d} of something that is not a coordinate"
                    )
            for f in atoms:
                if isinstance(f, sp.Symbol):
                    if f != t:
                        self._parameters.add(f)
                elif isinstance(f, AppliedUndef):
                    if (j := self._resolve(f)) is not None:
                        used.add(j)
                    elif self._ref(f, refs, problems) is not None:
                        pass
                    elif not any(f in d.atoms(AppliedUndef) for d in derivs):
                        problems.append(
                            f"depends on `{f}`, which is not a coordinate of this system "
                            f"(coordinates: {', '.join(map(str, self.coordinates))})"
                        )
        if problems:
            raise ModelError(f"{what}: " + "; ".join(dict.fromkeys(problems)))
        return tuple(sorted(used))

    def _ref(self, f: AppliedUndef, refs: dict | None, problems: list[str]) -> Ref | None:
        ref = find_ref(self.families, f) if self.families else None
        if ref is not None:
            if refs is None:
                problems.append(
                    f"uses the family reference {f.func.__name__}: pass `over={ref.index}` "
                    f"(or over=({ref.index}, first, last)) to instantiate it"
                )
            else:
                refs[f] = ref
        return ref

    def _coord(self, i: int) -> sp.Expr:
        """Coordinate i (O(1), without building the whole coordinate list)."""
        if i < len(self._ordinary):
            return self._ordinary[i]
        fam = next(f for f in self.families if f.offset <= i < f.offset + f.n)
        return fam.member(fam.first + i - fam.offset)

    def _localize(
        self, exprs: tuple[sp.Expr, ...], coords: tuple[int, ...], over: object = None, what=""
    ) -> tuple[tuple[sp.Expr, ...], Template | None]:
        """Local form of ``exprs``; for a family piece (``over``) also its :class:`Template`."""
        refs = self._pending_refs
        self._pending_refs = {}
        slots: list = list(coords)
        if over is not None:
            k, lo, hi = index_range(list(refs.values()), over, what)
            slots += list(refs.values())
            slots.sort(key=lambda s: s if isinstance(s, int) else s.column(lo))
        by_ref = {r: f for f, r in refs.items()}
        rule: dict[sp.Basic, sp.Basic] = {}
        for a, s_ in enumerate(slots):
            q = self._coord(s_) if isinstance(s_, int) else by_ref[s_]
            rule[speed(q)] = local_qd(a)
            rule[q] = local_q(a)
        local = tuple(e.xreplace(rule) for e in exprs)
        if over is None:
            return local, None
        if any(e.has(k) for e in local):
            raise ModelError(
                f"{what}: the index {k} appears outside a family reference; templates may "
                "use it only inside references such as theta[k + 1]"
            )
        return local, Template(k, lo, hi, tuple(slots))

    def _refs(self, over: object) -> dict | None:
        """Start collecting family references for a piece added with ``over``."""
        self._pending_refs = {}
        return self._pending_refs if over is not None else None

    def _add(
        self,
        kind: str,
        exprs: tuple,
        coords: tuple[int, ...],
        name: str,
        dim: int = 0,
        over: object = None,
        local: tuple | None = None,
        template: Template | None = None,
    ) -> Piece:
        if local is None:
            local, template = self._localize(exprs, coords, over, f"{kind} `{name}`")
        piece = Piece(kind, exprs, coords, (kind, dim, *local), name, dim, template)
        self.pieces.append(piece)
        self._counts[kind] += piece.count
        return piece

    def _vector(self, value: object, what: str, frame: object) -> tuple[sp.Expr, ...]:
        if is_physics_vector(value, "Vector"):
            frame = frame if frame is not None else self.frame
            if frame is None:
                frame = self._only_fixed_frame(value, what)
            comps = tuple(value.to_matrix(frame))
        elif isinstance(value, sp.MatrixBase):
            comps = tuple(value)
        elif isinstance(value, list | tuple) or hasattr(value, "__array__"):
            comps = tuple(value.tolist() if hasattr(value, "tolist") else value)
        else:
            raise ModelTypeError(
                f"{what} must be a list of 2 or 3 expressions, a Matrix or a "
                f"sympy.physics.vector.Vector, got {type(value).__name__}"
            )
        if len(comps) not in (2, 3):
            raise ModelError(
                f"{what} must have 2 or 3 components (planar or spatial), got {len(comps)}"
            )
        return tuple(as_expr(c, f"{what} component {i}") for i, c in enumerate(comps))

    @staticmethod
    def _only_fixed_frame(value: Vector, what: str) -> object:
        """The vector's single frame, when no coordinate or t turns it against its neighbours."""
        frames = {f for _, f in value.args}
        if len(frames) == 1:
            (f,) = frames
            moving = any(dcm.has(t) or dcm.atoms(AppliedUndef) for dcm in f._dcm_dict.values())
            if not moving:
                return f
        raise ModelError(
            f"{what} is a sympy.physics.vector.Vector and its inertial frame is ambiguous: pass "
            "`frame=N` (the inertial frame) here or to pfaff.System(..., frame=N)"
        )

    def _label(self, name: str | None, kind: str) -> str:
        if name is not None and not isinstance(name, str):
            raise ModelTypeError(f"`name` must be a string, got {name!r}")
        return name or f"{kind}{self._counts.get(kind, self.n_constraints) + 1}"

    # ------------------------------------------------------------------ building the model
    @checked_keywords
    def add_particle(
        self,
        mass: object,
        position: object,
        *,
        name: str | None = None,
        frame: object = None,
        over: object = None,
    ) -> None:
        """Add a point mass at ``position`` (inertial components, functions of q and t).

        Parameters
        ----------
        mass : Expr or float
            Constant mass (parameters only, no coordinates).
        position : sequence of 2 or 3 Expr, Matrix, or sympy.physics.vector.Vector
            Inertial position r(q, t). A Vector needs ``frame=`` when it spans several frames.
        name : str, optional
            Label used in reports.
        frame : ReferenceFrame, optional
            Inertial frame in which to take a Vector's components.
        over : Symbol or tuple, optional
            Make this a family template: ``k`` (every k of the family indexed as ``fam[k]``) or
            ``(k, first, last)`` (inclusive, as in :class:`sympy.Sum`); see :meth:`add_family`.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> th, = pfaff.coordinates("theta:1")
        >>> s = pfaff.System([th])
        >>> s.add_particle(1, [sp.sin(th), -sp.cos(th)])
        >>> s.equations().mass_matrix
        Matrix([[1]])
        """
        label = self._label(name, "particle")
        m = self._mass(mass, f"particle `{label}`")
        r = self._vector(position, f"position of particle `{label}`", frame)
        refs = self._refs(over)
        coords = self._scan(r, f"position of particle `{label}`", speeds=False, refs=refs)
        self._add("particle", (m, *r), coords, label, len(r), over)

    def _mass(self, mass: object, what: str) -> sp.Expr:
        """A constant, positive mass (parameters only, no coordinates)."""
        m = as_expr(mass, f"mass of {what}")
        if self._scan((m,), f"mass of {what}", speeds=False) or m.has(t):
            raise ModelError(f"mass of {what} must be constant, got {m}")
        if m.is_number and not m.is_positive:
            raise ModelError(f"mass of {what} must be positive, got {m}")
        return m

    @checked_keywords
    def add_kinetic_energy(
        self, expr: object, *, name: str | None = None, over: object = None
    ) -> None:
        """Add a kinetic energy term T(q, q̇, t) (e.g. ``I*theta.diff(t)**2/2``).

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> th = pfaff.coordinates("theta")
        >>> s = pfaff.System([th]); s.add_kinetic_energy(sp.Symbol("I") * th.diff(pfaff.t)**2)
        >>> s.equations().mass_matrix
        Matrix([[2*I]])
        """
        label = self._label(name, "kinetic")
        e = as_expr(expr, f"kinetic energy `{label}`")
        refs = self._refs(over)
        coords = self._scan((e,), f"kinetic energy `{label}`", speeds=True, refs=refs)
        if not coords and not refs:
            raise ModelError(f"kinetic energy `{label}` involves no coordinate: {e}")
        self._add("kinetic", (e,), coords, label, over=over)

    @checked_keywords
    def add_potential_energy(
        self, expr: object, *, name: str | None = None, over: object = None
    ) -> None:
        """Add a potential energy term V(q, t); the Lagrangian is L = T - V.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> y = pfaff.coordinates("y")
        >>> s = pfaff.System([y]); s.add_particle(2, [0, y]); s.add_potential_energy(2 * 9.81 * y)
        >>> s.equations().forcing
        Matrix([[-19.62]])
        """
        label = self._label(name, "potential")
        e = as_expr(expr, f"potential energy `{label}`")
        refs = self._refs(over)
        coords = self._scan((e,), f"potential energy `{label}`", speeds=False, refs=refs)
        if coords or refs:
            self._add("potential", (e,), coords, label, over=over)

    @checked_keywords
    def add_force(
        self,
        force: object,
        at: object,
        *,
        name: str | None = None,
        frame: object = None,
        over: object = None,
    ) -> None:
        """Add a force applied at the point with position ``at``.

        Its generalized force is Q_j = F · ∂ṙ/∂q̇_j = F · ∂r/∂q_j (partial velocities).

        Parameters
        ----------
        force : sequence of 2 or 3 Expr, Matrix or Vector
            Force components in the inertial frame; may depend on q, q̇ and t.
        at : sequence of 2 or 3 Expr, Matrix or Vector
            Position r(q, t) of the material point the force acts on.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x = pfaff.coordinates("x")
        >>> s = pfaff.System([x]); s.add_particle(1, [x, 0]); s.add_force([3, 0], at=[x, 0])
        >>> s.equations().generalized_forces
        Matrix([[3]])
        """
        label = self._label(name, "force")
        f = self._vector(force, f"force `{label}`", frame)
        r = self._vector(at, f"point of force `{label}`", frame)
        if len(f) != len(r):
            raise ModelError(f"force `{label}` has {len(f)} components but its point has {len(r)}")
        refs = self._refs(over)
        cf = self._scan(f, f"force `{label}`", speeds=True, refs=refs, smooth=False)
        cr = self._scan(r, f"point of force `{label}`", speeds=False, refs=refs)
        coords = tuple(sorted(set(cf) | set(cr)))
        self._add("force", (*f, *r), coords, label, len(f), over)

    @checked_keywords
    def add_generalized_force(
        self, coordinate: object, expr: object, *, name: str | None = None
    ) -> None:
        """Add ``expr`` to the generalized force Q of ``coordinate`` (a torque for an angle).

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> th = pfaff.coordinates("theta")
        >>> s = pfaff.System([th]); s.add_kinetic_energy(th.diff(pfaff.t)**2 / 2)
        >>> s.add_generalized_force(th, -th.diff(pfaff.t))
        >>> s.equations().forcing
        Matrix([[-Derivative(theta(t), t)]])
        """
        if coordinate not in self._index:
            raise ModelError(f"`{coordinate}` is not a coordinate of this system")
        label = self._label(name, "genforce")
        e = as_expr(expr, f"generalized force `{label}`")
        j = self._index[coordinate]
        coords = tuple(
            sorted(
                set(self._scan((e,), f"generalized force `{label}`", speeds=True, smooth=False))
                | {j}
            )
        )
        self._add("genforce", (e,), coords, label, coords.index(j))

    @checked_keywords
    def add_holonomic_constraint(
        self, expr: object, name: str | None = None, *, over: object = None
    ) -> None:
        """Add a holonomic constraint f(q, t) = 0; it enters as A = ∂f/∂q, b = ∂f/∂t.

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x, th = pfaff.coordinates("x theta")
        >>> s = pfaff.System([x, th]); s.add_holonomic_constraint(x - 2 * th, name="no slip")
        >>> s.equations().constraint_matrix
        Matrix([[1, -2]])
        """
        label = self._label(name, "constraint")
        if isinstance(expr, sp.Equality):
            expr = expr.lhs - expr.rhs
        e = as_expr(expr, f"constraint `{label}`")
        what = f"holonomic constraint `{label}`"
        refs = self._refs(over)
        coords = self._scan((e,), what, speeds=False, refs=refs)
        local, tmpl = self._localize((e,), coords, over, what)
        self._check_new_constraint(e, local, coords, label, tmpl)
        self._add("holonomic", (e,), coords, label, local=local, template=tmpl)

    @checked_keywords
    def add_velocity_constraint(
        self, expr: object, name: str | None = None, *, over: object = None
    ) -> None:
        """Add a Pfaffian velocity constraint A(q,t) q̇ + b(q,t) = 0 (linear in q̇).

        Examples
        --------
        >>> import sympy as sp, pfaff
        >>> x, th = pfaff.coordinates("x theta")
        >>> s = pfaff.System([x, th])
        >>> s.add_velocity_constraint(x.diff(pfaff.t) - 2 * th.diff(pfaff.t), name="rolling")
        >>> s.equations().constraint_matrix
        Matrix([[1, -2]])
        """
        label = self._label(name, "constraint")
        e = as_expr(expr, f"constraint `{label}`")
        what = f"velocity constraint `{label}`"
        refs = self._refs(over)
        coords = self._scan((e,), what, speeds=True, refs=refs)
        (local,), tmpl = self._localize((e,), coords, over, what)
        slots = coords if tmpl is None else tmpl.slots
        uds = [local_qd(a) for a in range(len(slots))]
        present = [u for u in uds if local.has(u)]
        if not present:
            raise ConstraintError(
                f"velocity constraint `{label}` contains no velocity; a relation among coordinates "
                "is holonomic: use add_holonomic_constraint"
            )
        nonlinear = [
            str(_slot_name(self, slots[uds.index(u)])) for u in present if local.diff(u).has(*uds)
        ]
        if nonlinear:
            raise ConstraintError(
                f"velocity constraint `{label}` is not Pfaffian: it is not linear in the "
                f"velocities ({', '.join(nonlinear)}); write it as A(q,t)·q̇ + b(q,t) = 0"
            )
        self._check_new_constraint(e, (local,), coords, label, tmpl)
        self._add("velocity", (e,), coords, label, local=(local,), template=tmpl)

    def _check_new_constraint(
        self,
        e: sp.Expr,
        local: tuple[sp.Expr, ...],
        coords: tuple[int, ...],
        label: str,
        tmpl: Template | None = None,
    ) -> None:
        if not coords and tmpl is None:
            raise ConstraintError(f"constraint `{label}` names no coordinate: {e} = 0")
        key = (*local, coords if tmpl is None else tmpl)
        if key in self._constraint_keys:
            raise ConstraintError(
                f"constraint `{label}` repeats constraint `{self._constraint_keys[key]}` exactly: "
                "it carries no information (constraints that depend on one another otherwise are "
                "accepted and reported: pfaff.RedundancyWarning)"
            )
        self._constraint_keys[key] = label

    def __repr__(self) -> str:
        counts = {k: sum(p.kind == k for p in self.pieces) for k in PIECE_KINDS}
        parts = ", ".join(f"{v} {k}" for k, v in counts.items() if v)
        return f"<pfaff.System '{self.name}': {self.n} coordinates{', ' + parts if parts else ''}>"
