"""The geometry of a compiled model: where its particles and bodies are, as functions of (q, t).

A :class:`Geometry` is what an animation draws (:mod:`pfaff.results.animation`). It is built from
the model's pieces when the model is compiled (:func:`build_geometry`) and evaluates, from
coordinates alone, with NumPy:

- ``points(q, t)``: the particles, in the order they were added (a family template's instances
  subsampled to at most :data:`MAX_POINTS`, evenly over its index range), then the points where
  forces act; shape (..., P, d), d = 2 (planar) or 3;
- ``bodies(q, t)``: each rigid body's mass centre, shape (..., B, d), and direction cosine matrix
  C (r_inertial = C r_body), shape (..., B, 3, 3);
- ``links``: the pairs of points a line joins (-1 is the fixed origin).

Each distinct local form is turned into code once (``lambdify``, on first use: compiling a model
costs no code generation for its geometry) and runs over all its instances at once; parameter
values are arguments of that code (:meth:`Geometry.with_parameters` shares it).

The link rule
-------------
Two points (or a point and the origin) are linked when the model fixes their distance: ``|rᵢ −
rⱼ|²`` is the same at random configurations (a rod built into the positions: a pendulum in its
angle, the links of a chain, a top's axis), or equals ``c + s·f`` for one holonomic constraint
``f`` (a rod written as a constraint: ``x² + y² − L² = 0``). Pairs of fixed points, and points that
coincide, are not linked. Only systems of at most :data:`LINK_POINTS` points (not counting family
instances) are searched; a family is drawn as its points, its centre and a spoke to its first
drawn member instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ParameterError, StateError
from pfaff.core.symbols import local_q, t

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation
    from pfaff.mechanics.bodies import Body
    from pfaff.mechanics.shapes import Shape
    from pfaff.mechanics.system import Piece, SystemSpec

MAX_POINTS = 2000  # drawn instances of one family template at most
LINK_POINTS = 24  # link search only for systems with at most this many (non-family) points
_SAMPLES = 8  # random configurations of the link search


@dataclass
class _Group:
    """Points sharing one local form: ``exprs`` in ``_q0 … _q{k-1}``, t and the parameters."""

    k: int
    exprs: tuple[sp.Expr, ...]
    cols: list[tuple[int, ...]] = field(default_factory=list)  # global columns per instance
    slots: list[int] = field(default_factory=list)  # index of each instance among the points


@dataclass
class _Code:
    """The compiled form of a geometry, shared by its copies with other parameter values."""

    groups: list[tuple[Callable, np.ndarray, np.ndarray, int]]  # fn, local cols, slots, dim
    bodies: list[tuple[Callable, np.ndarray]]  # fn, local cols (centre, then C row by row)
    constraints: list[tuple[Callable, np.ndarray]]  # fn, local cols into the link columns


class Geometry:
    """Positions of a model's particles and bodies as plain NumPy functions of (q, t).

    Made by :func:`build_geometry` when a model is compiled (``model.geometry``) and carried by
    the trajectories that :func:`pfaff.simulate` returns.

    Attributes
    ----------
    name : str
        The system's name.
    n : int
        Number of coordinates of the model.
    dim : int
        2 (planar) or 3.
    names : list of str, length P
        One per point: the particle's name (``"particle 17"`` for member 17 of a family template),
        or the force's.
    kinds : list of str, length P
        ``"particle"``, ``"family"`` (a subsampled family instance) or ``"force"``.
    families : list of (str, int, int)
        Per family template: its name and the range [start, stop) of its points.
    body_names : list of str, length B
    planar_bodies : list of bool, length B
    columns : ndarray of int
        The coordinates the geometry reads, ascending (a few thousand at most, however large the
        model).
    parameters : dict of str to float

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
    >>> geo = model.geometry
    >>> geo.names, geo.points([np.pi / 2]).round(12) + 0.0
    (['bob'], array([[2., 0.]]))
    >>> geo.links
    [(-1, 0)]
    """

    def __init__(
        self,
        system: SystemSpec,
        groups: list[_Group],
        bodies: list[tuple[str, bool, tuple[int, ...], tuple[sp.Expr, ...]]],
        constraints: list[tuple[tuple[int, ...], sp.Expr]],
        names: list[str],
        kinds: list[str],
        families: list[tuple[str, int, int]],
        params: tuple[sp.Symbol, ...],
        values: Sequence[float],
        dim: int,
        sizes: list[tuple[str, tuple[sp.Expr, ...]]] | None = None,
    ) -> None:
        self.name = str(system.name)
        self.n = int(system.n)
        self.dim = dim
        self.names, self.kinds, self.families = names, kinds, families
        self.body_names = [b[0] for b in bodies]
        self._sizes = list(sizes or [])
        self.planar_bodies = [b[1] for b in bodies]
        self._groups, self._bodies, self._constraints = groups, bodies, constraints
        self._params = params
        self._values = np.array(values, dtype=float)
        used = [c for g in groups for row in g.cols for c in row] + [
            c for b in bodies for c in b[2]
        ]
        self.columns = np.unique(np.array(used, dtype=np.int64))
        cons = [c for cols, _ in constraints for c in cols]
        self._link_columns = np.unique(np.concatenate([self.columns, np.array(cons, np.int64)]))
        self._quaternions = [
            np.array([system._index[q] for q in b.attitude.coordinates], dtype=np.int64)
            for b in system.bodies
            if b.attitude.kind == "quaternion"
        ]
        self._code: _Code | None = None
        self._links: list[tuple[int, int]] | None = None

    # ------------------------------------------------------------------ parameters
    @property
    def parameters(self) -> dict[str, float]:
        """Parameter values by name."""
        return {p.name: float(v) for p, v in zip(self._params, self._values, strict=True)}

    def with_parameters(self, parameters: dict[str, float]) -> Geometry:
        """The same geometry (and compiled code) with other parameter values, by name.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.pendulum().equations().compile({"m": 1, "g": 9.81, "L": 2})
        >>> model.geometry.with_parameters({"L": 3}).points([0.0]).round(12) + 0.0
        array([[ 0., -3.]])
        """
        new = object.__new__(Geometry)
        new.__dict__.update(self.__dict__)
        values = self._values.copy()
        index = {p.name: i for i, p in enumerate(self._params)}
        for key, v in parameters.items():
            if str(key) not in index:
                raise ParameterError(f"unknown parameter `{key}` (the model's: {', '.join(index)})")
            values[index[str(key)]] = float(v)
        new._values = values
        return new

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_code"] = None  # generated functions do not pickle: made again on first use
        return state

    def __repr__(self) -> str:
        return (
            f"<pfaff.Geometry '{self.name}': {len(self.names)} points, "
            f"{len(self.body_names)} bodies, {self.dim}-D>"
        )

    # ------------------------------------------------------------------ evaluation
    def _compiled(self) -> _Code:
        if self._code is None:
            args = [t, *self._params]
            groups = []
            for g in self._groups:
                fn = _lambdify([*map(local_q, range(g.k)), *args], g.exprs)
                cols = np.searchsorted(
                    self.columns, np.array(g.cols, np.int64).reshape(len(g.cols), g.k)
                )
                groups.append((fn, cols, np.array(g.slots, np.int64), len(g.exprs)))
            bodies = [
                (
                    _lambdify([*map(local_q, range(len(cols_))), *args], exprs),
                    np.searchsorted(self.columns, np.array(cols_, np.int64)),
                )
                for _, _, cols_, exprs in self._bodies
            ]
            cons = []
            for cols_, expr in self._constraints:
                fn = _lambdify([*map(local_q, range(len(cols_))), *args], [expr])
                cons.append((fn, np.searchsorted(self._link_columns, np.array(cols_, np.int64))))
            self._code = _Code(groups, bodies, cons)
        return self._code

    def _restrict(self, q: object) -> np.ndarray:
        """q's columns that the geometry reads; q has n columns or already only those."""
        qa = np.asarray(q, dtype=float)
        if qa.ndim == 0 or qa.shape[-1] not in (self.n, len(self.columns)):
            raise StateError(
                f"`q` must have {self.n} coordinates (or the {len(self.columns)} of `columns`) "
                f"in its last axis, got shape {qa.shape}"
            )
        return qa[..., self.columns] if qa.shape[-1] == self.n else qa

    def points(self, q: object, t: object = 0.0) -> np.ndarray:
        """Inertial positions of the points.

        Parameters
        ----------
        q : array_like, shape (..., n) or (..., len(columns))
            Coordinates (all of them, or only those of :attr:`columns`, in that order).
        t : float or array_like, shape (...)
            Time (for positions that depend on it).

        Returns
        -------
        ndarray, shape (..., P, dim)
        """
        qc = self._restrict(q)
        lead = qc.shape[:-1]
        tt = np.broadcast_to(np.asarray(t, dtype=float), lead)[..., None]
        out = np.zeros((*lead, len(self.names), self.dim))
        with np.errstate(all="ignore"):
            for fn, cols, slots, _ in self._compiled().groups:
                args = [qc[..., cols[:, a]] for a in range(cols.shape[1])]
                for j, v in enumerate(fn(*args, tt, *self._values)):
                    out[..., slots, j] = np.broadcast_to(v, (*lead, len(slots)))
        return out

    __call__ = points

    def bodies(self, q: object, t: object = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Mass centres and direction cosine matrices of the rigid bodies.

        Parameters
        ----------
        q, t
            As in :meth:`points`.

        Returns
        -------
        centres : ndarray, shape (..., B, dim)
        dcm : ndarray, shape (..., B, 3, 3)
            C of each body: its columns are the body axes in inertial components.

        Examples
        --------
        >>> import numpy as np, pfaff
        >>> model = pfaff.models.torque_free_body("euler").equations().compile(
        ...     {"I1": 1, "I2": 2, "I3": 3})
        >>> centres, dcm = model.geometry.bodies([np.pi / 2, 0.0, 0.0])  # 3-2-1: 90° about z
        >>> dcm[0].round(12) + 0.0
        array([[ 0., -1.,  0.],
               [ 1.,  0.,  0.],
               [ 0.,  0.,  1.]])
        """
        qc = self._restrict(q)
        lead = qc.shape[:-1]
        B = len(self._bodies)
        centres, dcm = np.zeros((*lead, B, self.dim)), np.zeros((*lead, B, 3, 3))
        tt = np.broadcast_to(np.asarray(t, dtype=float), lead)
        for k, (fn, cols) in enumerate(self._compiled().bodies):
            with np.errstate(all="ignore"):
                vals = fn(*(qc[..., c] for c in cols), tt, *self._values)
            vals = [np.broadcast_to(v, lead) for v in vals]
            centres[..., k, :] = np.stack(vals[: self.dim], axis=-1)
            dcm[..., k, :, :] = np.stack(vals[self.dim :], axis=-1).reshape((*lead, 3, 3))
        return centres, dcm

    def sizes(self) -> list[tuple[str, np.ndarray]]:
        """What sizes each drawn solid, at the parameter values.

        Returns
        -------
        list of (str, ndarray), length B
            ``("inertia", [m, I₁₁, I₁₂, …, I₃₃])`` for a rigid body (or a shape given by its
            inertia), ``("ellipsoid" | "box", [a, b, c])`` (semi-axes) for a shape given by size.

        Examples
        --------
        >>> import pfaff
        >>> model = pfaff.models.torque_free_body("euler").equations().compile(
        ...     {"I1": 1, "I2": 2, "I3": 3})
        >>> kind, v = model.geometry.sizes()[0]
        >>> kind, v.tolist()
        ('inertia', [1.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0])
        """
        out = []
        for kind, exprs in self._sizes:
            fn = sp.lambdify(list(self._params), list(exprs), modules="numpy", docstring_limit=0)
            with np.errstate(all="ignore"):
                vals = np.array(fn(*self._values), dtype=float).reshape(-1)
            out.append((kind, vals))
        return out

    # ------------------------------------------------------------------ links
    @property
    def links(self) -> list[tuple[int, int]]:
        """Pairs (i, j) of point indices joined by a line; -1 is the fixed origin (module doc)."""
        if self._links is None:
            self._links = self._find_links()
        return list(self._links)

    def _find_links(self) -> list[tuple[int, int]]:
        cand = [i for i, k in enumerate(self.kinds) if k != "family"]
        if len(cand) < 1 or len(cand) > LINK_POINTS:
            return []
        code = self._compiled()
        rng = np.random.default_rng(20240601)
        qa = rng.uniform(-2.0, 2.0, (_SAMPLES, len(self._link_columns)))
        for cols in self._quaternions:  # a quaternion's unit norm holds at every sample
            ix = np.searchsorted(self._link_columns, cols)
            qa[:, ix] /= np.linalg.norm(qa[:, ix], axis=1, keepdims=True)
        ts = rng.uniform(0.0, 1.0, _SAMPLES)
        pts = self.points(qa[:, np.searchsorted(self._link_columns, self.columns)], ts)
        pts = np.concatenate([np.zeros((_SAMPLES, 1, self.dim)), pts[:, cand]], axis=1)
        index = [-1, *cand]
        fixed = np.ptp(pts, axis=0).max(axis=1) <= 1e-9 * max(1.0, np.abs(pts).max())
        pairs = [
            (a, b)
            for a in range(len(index))
            for b in range(a + 1, len(index))
            if not (fixed[a] and fixed[b])
        ]
        if not pairs:
            return []
        ia, ib = np.array(pairs).T
        d2 = ((pts[:, ia] - pts[:, ib]) ** 2).sum(axis=-1)  # (samples, pairs)
        with np.errstate(all="ignore"):
            tol = 1e-9 * np.maximum(1.0, np.abs(d2).max(axis=0))
            linked = (np.ptp(d2, axis=0) <= tol) & (np.abs(d2).max(axis=0) > tol)
            for fn, cols in code.constraints:
                f = np.broadcast_to(
                    fn(*(qa[:, c] for c in cols), ts, *self._values)[0], (_SAMPLES,)
                )
                if not np.isfinite(f).all() or np.ptp(f) <= 1e-9 * max(1.0, np.abs(f).max()):
                    continue
                X = np.column_stack([np.ones(_SAMPLES), f])
                ok = np.isfinite(d2).all(axis=0)
                coef = np.linalg.lstsq(X, np.where(ok, d2, 0.0), rcond=None)[0]
                resid = np.abs(d2 - X @ coef).max(axis=0)
                linked |= ok & (resid <= tol) & (np.abs(coef[0]) > tol)
        return [(index[ia[p]], index[ib[p]]) for p in np.flatnonzero(linked)]


def _lambdify(args: list, exprs: Sequence[sp.Expr]) -> Callable:
    return sp.lambdify(args, list(exprs), modules="numpy", cse=True, docstring_limit=0)


def _point_exprs(piece: Piece) -> tuple[sp.Expr, ...]:
    """The local position of a particle, or of a force's point."""
    local = piece.key[2:]
    return tuple(local[1:]) if piece.kind == "particle" else tuple(local[piece.dim :])


def _instances(piece: Piece) -> tuple[list[tuple[int, ...]], list[int]]:
    """Global columns and indices (k) of the drawn instances of a piece."""
    tmpl = piece.template
    if tmpl is None:
        return [piece.coords], [0]
    step = math.ceil(tmpl.count / MAX_POINTS)
    inst = np.arange(0, tmpl.count, step, dtype=np.int64)
    prog = [tmpl.progression(a) for a in range(len(tmpl.slots))]
    cols = np.stack([s + d * inst for s, d in prog], axis=1) if prog else np.zeros((len(inst), 0))
    return [tuple(r) for r in cols.tolist()], (inst + tmpl.lo).tolist()


def _body(
    system: SystemSpec, body: Body | Shape, dim: int
) -> tuple[str, bool, tuple[int, ...], tuple]:
    """(name, planar, coordinate columns, local exprs: centre (dim), then C row by row)."""
    centre = [*body.position] + [sp.S.Zero] * (dim - body.position.rows)
    exprs = [*centre, *body.dcm]
    funcs = sorted(
        {f for e in exprs for f in e.atoms(AppliedUndef) if system._resolve(f) is not None},
        key=system._resolve,
    )
    cols = tuple(system._resolve(f) for f in funcs)
    rule = {f: local_q(a) for a, f in enumerate(funcs)}
    local = tuple(sp.sympify(e).xreplace(rule) for e in exprs)
    attitude = getattr(body, "attitude", None)
    planar = attitude.kind == "planar" if attitude is not None else body.position.rows == 2
    return body.name, planar, cols, local


def build_geometry(eom: Derivation, values: Sequence[float]) -> Geometry | None:
    """The :class:`Geometry` of ``eom``'s system with ordered parameter values, or None when
    there is nothing to draw (no particles or bodies, or equations given as matrices).

    Cheap: it groups pieces by their local form; code is made on first use.

    Examples
    --------
    >>> import pfaff
    >>> eom = pfaff.models.rolling_ring(100_000, force=True).equations()
    >>> geo = build_geometry(eom, [2.0, 1.0, 0.5])
    >>> len(geo.names), geo.kinds[-1], geo.families
    (2001, 'force', [('particle', 0, 2000)])
    """
    system = getattr(eom, "system", None)
    pieces = [p for p in getattr(system, "pieces", ()) if p.kind == "particle"]
    shapes = list(getattr(system, "shapes", ()))
    if system is None or not (pieces or shapes or system.bodies):
        return None
    pieces += [p for p in system.pieces if p.kind == "force" and p.template is None]
    groups: dict[tuple, _Group] = {}
    names: list[str] = []
    kinds: list[str] = []
    families: list[tuple[str, int, int]] = []
    for piece in pieces:
        exprs = _point_exprs(piece)
        cols, ks = _instances(piece)
        k = len(cols[0])
        g = groups.setdefault((k, exprs), _Group(k, exprs))
        start = len(names)
        g.cols += cols
        g.slots += list(range(start, start + len(cols)))
        if piece.template is None:
            names.append(piece.name)
            kinds.append("particle" if piece.kind == "particle" else "force")
        else:
            names += [f"{piece.name} {i}" for i in ks]
            kinds += ["family"] * len(ks)
            families.append((piece.name, start, len(names)))
    dims = [len(g.exprs) for g in groups.values()] + [s.position.rows for s in shapes]
    dim = max(dims, default=3)  # bodies alone: spatial
    solids = [*system.bodies, *shapes]
    bodies = [_body(system, body, dim) for body in solids]
    linkable = sum(k != "family" for k in kinds)
    constraints = []
    if linkable <= LINK_POINTS:
        constraints = [
            (p.coords, p.key[2])
            for p in system.pieces
            if p.kind == "holonomic" and p.template is None
        ][: 4 * LINK_POINTS]
    return Geometry(
        system,
        list(groups.values()),
        bodies,
        constraints,
        names,
        kinds,
        families,
        tuple(eom.parameters),
        values,
        dim,
        [_size_exprs(b) for b in solids],
    )


def _size_exprs(body: Body | Shape) -> tuple[str, tuple[sp.Expr, ...]]:
    """What sizes a drawn solid: ``("inertia", (m, I row by row))`` or ``(kind, semi-axes)``."""
    kind = getattr(body, "kind", None)
    if kind is not None:
        return kind, tuple(body.size)
    return "inertia", (body.mass, *body.inertia)
