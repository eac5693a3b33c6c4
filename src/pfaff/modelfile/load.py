"""Model files: a system described in TOML, read without running anything the file says.

The file is untrusted input. Its size is capped before it is read whole; TOML is parsed by the
standard library's ``tomllib`` (data only); every expression goes through
:func:`pfaff.core.safe_expr.parse_expression` (an ``ast`` whitelist that builds SymPy objects
directly: no ``eval``, ``sympify`` or ``parse_expr``); every name is a declared coordinate,
parameter, family or body, or ``t``. Errors name the file, the key and the problem.

The format (see ``examples/`` and the README)::

    [model]
    name = "double pendulum"
    coordinates = ["theta1", "theta2"]
    parameters = { m1 = 1.0, l1 = 1.0, g = 9.81 }
    kinetic = "..."            # optional energy terms (a string or a list of strings)
    potential = "..."
    dissipation = "..."        # a Rayleigh function R(q, dot(q)): Q = -dR/d(dot q)

    [[inputs]]                 # a named expression of t, q, dot(q) and the parameters,
    name = "u"                 # usable in every expression after it (a drive, a feedback law)
    value = "F0*sin(w*t) - k*dot(x)"

    [[families]]               # indexed coordinates theta0 ... theta{n-1} (first = 0)
    name = "theta"
    n = 8
    first = 0

    [[particles]]              # mass, position = [x, y(, z)], optional name and over
    [[bodies]]                 # mass, inertia, position, attitude = "euler" | "quaternion" |
                               # "mrp" | "planar", coordinates = [...], sequence = "321", name
    [[forces]]                 # force = [...], at = [...]
    [[generalized_forces]]     # coordinate, expr
    [[torques]]                # torque = [...] (or one expression for a planar body), on, frame
    [[springs]]                # k, between = [[...], [...]], rest_length
    [[dampers]]                # c, between
    [[constraints]]            # name, and holonomic = "f(q, t)" or velocity = "A(q) dot(q) + b"
    [[contacts]]               # gap = "g(q, t)" (>= 0), restitution (a number or expression), name
    [[events]]                 # condition = "g(q, dot(q), t)", name, direction (-1, 0, 1), terminal

    [initial]
    q = { theta1 = 1.0 }       # a family takes a list of n values, or one value for all
    qd = { theta1 = 0.0 }

    [simulate]
    t_end = 10.0
    method = "projection"

A piece over a family has ``over = "k"`` (every k its references allow) or ``over = ["k", first,
last]``; its expressions write members as ``theta[k]``, ``theta[k+1]``. ``dot(q)`` is the rate of
coordinate q, ``t`` the time.

An input's value is substituted where the input is used, so a file's input is part of the
equations (``linearize`` sees the closed loop; for an open input, declare it in Python with
:meth:`pfaff.System.add_input`). A declared parameter or input that nothing uses is reported as a
:class:`pfaff.ModelWarning` naming it (its value would be ignored).
"""

from __future__ import annotations

import math
import os
import tomllib
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from pfaff.api.system import System
from pfaff.core.errors import ModelError, ModelWarning, ParameterError
from pfaff.core.files import file_path, read_capped
from pfaff.core.keywords import checked_keywords
from pfaff.core.safe_expr import (
    ExpressionError,
    check_name,
    parse_expression,
    parse_number,
)
from pfaff.core.stack import outside_pfaff
from pfaff.core.symbols import coordinates as make_coordinates
from pfaff.core.symbols import t
from pfaff.mechanics.attitude import MRP, EulerAngles, PlanarAngle, Quaternion

MAX_BYTES = 1 << 20  # 1 MB: a larger file is refused unless ``max_bytes`` is raised
SECTIONS = {
    "model", "inputs", "families", "particles", "bodies", "forces", "generalized_forces", "torques",
    "springs", "dampers", "constraints", "contacts", "events", "initial", "simulate",
}  # fmt: skip
SIMULATE_KEYS = {
    "t_end": float, "method": str, "rtol": float, "atol": float, "integrator": str,
    "max_step": float, "first_step": float, "alpha": float, "beta": float,
    "constraint_tol": float, "initial_tol": float, "project_initial": bool,
    "project_output": bool, "samples": int, "rest_speed": float, "max_steps": int,
    "max_seconds": float,
}  # fmt: skip


class ModelFileError(ModelError):
    """A model file that cannot be read: the message names the file, the key and the problem."""


@dataclass
class ModelFile:
    """A model file, read.

    Attributes
    ----------
    path : Path
    name : str
    system : System
    parameters : dict of str to float
        The values of ``[model].parameters``, in the file's order.
    q0, qd0 : ndarray, shape (n,)
        ``[initial]`` in coordinate order (0 where not given).
    simulate : dict
        ``[simulate]``: run settings (``t_end``, ``method``, tolerances, ...).
    constraint_names : list of str
        In the file's order (the order of the multipliers).
    inputs : dict of str to Expr
        ``[[inputs]]``: each input's value, in the file's order (substituted where it is used).
    """

    path: Path
    name: str
    system: System
    parameters: dict[str, float]
    q0: np.ndarray
    qd0: np.ndarray
    simulate: dict[str, Any] = field(default_factory=dict)
    constraint_names: list[str] = field(default_factory=list)
    inputs: dict[str, sp.Expr] = field(default_factory=dict)

    def compile(self, **parameters: float) -> Any:
        """The numeric model with the file's parameter values (``parameters`` override them).

        Raises
        ------
        ParameterError
            An override names no parameter of the file.

        Warns
        -----
        ModelWarning
            Naming each declared parameter that no expression of the model uses (its value is
            left out: it would change nothing).
        """
        unknown = sorted(set(parameters) - set(self.parameters))
        if unknown:
            raise ParameterError(
                f"file {self.path}: {', '.join(f'`{k}`' for k in unknown)} is not a parameter "
                f"of the file (its parameters: {', '.join(self.parameters) or 'none'})"
            )
        values = {**self.parameters, **parameters}
        used = {s.name for s in self.system.parameters}
        warn_unused(self.path, [k for k in values if k not in used])
        return self.system.equations().compile({k: v for k, v in values.items() if k in used})


def warn_unused(path: Path, names: list[str], what: str = "parameter") -> None:
    """A :class:`ModelWarning` naming the declared ``names`` that no expression uses."""
    if names:
        listed, many = ", ".join(f"`{n}`" for n in names), len(names) > 1
        warnings.warn(
            f"file {path}: {what}{'s' if many else ''} {listed} declared but not used by any "
            f"expression of the model: {'their values change' if many else 'its value changes'} "
            "nothing",
            ModelWarning,
            stacklevel=outside_pfaff(),
        )


@checked_keywords
def load_model(path: str | os.PathLike, *, max_bytes: int = MAX_BYTES) -> ModelFile:
    """Read a model file (TOML) into a :class:`ModelFile`; nothing in the file is executed.

    Parameters
    ----------
    path : str or PathLike
    max_bytes : int
        Largest accepted file size (1 MB by default).

    Raises
    ------
    ModelFileError
        Naming the file, the key (and line, for TOML syntax) and the problem.

    Examples
    --------
    >>> import pathlib, tempfile, pfaff
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "pendulum.toml"
    >>> _ = p.write_text('''
    ... [model]
    ... coordinates = ["theta"]
    ... parameters = { m = 1.0, l = 2.0, g = 9.81 }
    ... potential = "-m*g*l*cos(theta)"
    ... [[particles]]
    ... mass = "m"
    ... position = ["l*sin(theta)", "-l*cos(theta)"]
    ... [initial]
    ... q = { theta = 0.5 }
    ... ''')
    >>> mf = pfaff.load_model(p)
    >>> mf.system.equations().mass_matrix, mf.q0.tolist()
    (Matrix([[l**2*m]]), [0.5])
    """
    p = file_path(path)
    data = _read(p, max_bytes)
    return _Loader(p, data).load()


def _read(p: Path, max_bytes: int) -> dict:
    where = f"file {p}"
    hint = (
        " (pass a larger `max_bytes` to load_model, or --max-bytes, if the file is meant to be"
        " this large)"
    )
    text = read_capped(p, max_bytes, where, ModelFileError, hint)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ModelFileError(f"{where}: not valid TOML: {e}") from None
    except ValueError as e:  # Python's own limit on the digits of an integer
        raise ModelFileError(
            f"{where}: a number has more digits than Python reads ({str(e).split(';')[0]})"
        ) from None
    except RecursionError:
        raise ModelFileError(f"{where}: nested too deeply") from None


class _Names(Mapping):
    """The names an expression may use: the declared ones, and family members (``theta5``)
    resolved on demand (a family of 2^24 members is not listed)."""

    def __init__(self, declared: dict, families: dict, seen: set[str] | None = None) -> None:
        self.declared, self.families = declared, families
        self.seen = set() if seen is None else seen  # the names looked up (what is used)

    def __getitem__(self, key: str) -> sp.Expr:
        if key in self.declared:
            self.seen.add(key)
            return self.declared[key]
        for name, fam in self.families.items():
            rest = key[len(name) :]
            if key.startswith(name) and rest.isdigit() and (rest == "0" or rest[0] != "0"):
                i = int(rest)
                if fam.first <= i <= fam.last:
                    return fam[i]
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self.declared)

    def items(self) -> Any:
        """The declared names and values (listing them is not using them: nothing is seen)."""
        return self.declared.items()

    def __len__(self) -> int:
        return len(self.declared)


class _Loader:
    """One pass over the file's tables, building the System as it goes."""

    def __init__(self, path: Path, data: dict) -> None:
        self.path, self.data = path, data
        self.names: dict[str, sp.Expr] = {"t": t}
        self.families: dict[str, Any] = {}
        self.bodies: dict[str, Any] = {}
        self.constraints: list[str] = []
        self.inputs: dict[str, sp.Expr] = {}
        self.seen: set[str] = set()  # names the model's expressions use (not the inputs' own)

    def where(self, key: str) -> str:
        return f"file {self.path}, key {key}"

    def fail(self, key: str, problem: str) -> ModelFileError:
        return ModelFileError(f"{self.where(key)}: {problem}")

    # ------------------------------------------------------------------ helpers
    def table(self, key: str, value: object) -> dict:
        if not isinstance(value, dict):
            raise self.fail(key, f"must be a table, got {type(value).__name__}")
        return value

    def tables(self, key: str) -> list[dict]:
        value = self.data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.fail(key, f"must be an array of tables ([[{key}]])")
        return value

    def keys(
        self, key: str, tab: dict, allowed: set[str], required: set[str] = frozenset()
    ) -> None:
        extra = sorted(set(tab) - allowed)
        if extra:
            raise self.fail(
                key, f"unknown key(s) {', '.join(extra)} (allowed: {', '.join(sorted(allowed))})"
            )
        missing = sorted(required - set(tab))
        if missing:
            raise self.fail(key, f"missing key(s) {', '.join(missing)}")

    def expr(self, key: str, value: object, *, index: sp.Symbol | None = None) -> sp.Expr:
        if isinstance(value, bool):
            raise self.fail(key, f"must be an expression or a number, got {value!r}")
        if isinstance(value, int | float):
            return (
                sp.Integer(value)
                if isinstance(value, int)
                else sp.Float(parse_number(value, self.where(key)))
            )
        if not isinstance(value, str):
            raise self.fail(
                key, f"must be an expression (a string) or a number, got {type(value).__name__}"
            )
        names: Mapping = _Names(dict(self.names), self.families, self.seen)
        subs = None
        if index is not None:
            names.declared[index.name] = index
            subs = {name: (lambda i, fam=fam: fam[i]) for name, fam in self.families.items()}
        return parse_expression(value, names, where=self.where(key), subscripts=subs)

    def exprs(
        self, key: str, value: object, *, index: sp.Symbol | None = None, sizes=(2, 3)
    ) -> list:
        if not isinstance(value, list) or len(value) not in sizes:
            raise self.fail(key, f"must be a list of {' or '.join(map(str, sizes))} expressions")
        return [self.expr(f"{key}[{i}]", v, index=index) for i, v in enumerate(value)]

    def over(self, key: str, tab: dict) -> tuple[object, sp.Symbol | None]:
        if "over" not in tab:
            return None, None
        o = tab["over"]
        if isinstance(o, str):
            check_name(o, self.where(f"{key}.over"))
            k = sp.Symbol(o)
            return k, k
        if (
            isinstance(o, list)
            and len(o) == 3
            and isinstance(o[0], str)
            and all(isinstance(v, int) and not isinstance(v, bool) for v in o[1:])
        ):
            check_name(o[0], self.where(f"{key}.over"))
            k = sp.Symbol(o[0])
            return (k, o[1], o[2]), k
        raise self.fail(f"{key}.over", 'must be "k" or ["k", first, last] (whole numbers)')

    def name_of(self, key: str, tab: dict) -> str | None:
        name = tab.get("name")
        if name is not None and not isinstance(name, str):
            raise self.fail(f"{key}.name", "must be a string")
        if name is not None and (len(name) > 200 or not name.isprintable()):
            raise self.fail(f"{key}.name", "must be printable text of at most 200 characters")
        return name

    # ------------------------------------------------------------------ sections
    def load(self) -> ModelFile:
        unknown = sorted(set(self.data) - SECTIONS)
        if unknown:
            raise ModelFileError(
                f"file {self.path}: unknown section(s) {', '.join(unknown)} "
                f"(allowed: {', '.join(sorted(SECTIONS))})"
            )
        model = self.table("model", self.data.get("model", {}))
        self.keys(
            "model",
            model,
            {"name", "coordinates", "parameters", "kinetic", "potential", "dissipation"},
        )
        name = model.get("name", self.path.stem)
        if not isinstance(name, str):
            raise self.fail("model.name", "must be a string")
        system = self.system(model, name)
        values = self.parameters(model)
        uses = self.inputs_()
        self.energies(system, model)
        self.particles(system)
        self.bodies_(system)
        self.forces(system)
        self.constraints_(system)
        self.contacts_(system)
        self.events_(system)
        used = {s.name for s in system.parameters}
        undeclared = sorted(used - set(values))
        if undeclared:  # cannot happen through the parser; a guard against a future change
            raise self.fail("model.parameters", f"no value for {', '.join(undeclared)}")
        q0, qd0 = self.initial(system)
        self.unused(uses, values, used)
        return ModelFile(
            self.path,
            name,
            system,
            values,
            q0,
            qd0,
            self.simulate(),
            list(self.constraints),
            dict(self.inputs),
        )

    def inputs_(self) -> dict[str, set[str]]:
        """``[[inputs]]``: each a name for its value, an expression of t, q, dot(q), the
        parameters and the inputs before it; the names each value uses."""
        uses = {}
        for i, tab in enumerate(self.tables("inputs")):
            key = f"inputs[{i}]"
            self.keys(key, tab, {"name", "value"}, {"name", "value"})
            name = tab["name"]
            check_name(name, self.where(f"{key}.name"))
            if name in self.names or name in self.families:
                raise self.fail(
                    f"{key}.name", f"`{name}` is already a coordinate, parameter, input or family"
                )
            outer, self.seen = self.seen, set()
            self.inputs[name] = self.names[name] = self.expr(f"{key}.value", tab["value"])
            self.seen, uses[name] = outer, self.seen
        return uses

    def unused(self, uses: dict[str, set[str]], values: dict, used: set[str]) -> None:
        """Warn of the inputs and parameters that nothing uses (an input counts where the
        model's expressions use it, or an input they use does)."""
        live = {n for n in uses if n in self.seen}
        todo = list(live)
        while todo:
            for dep in uses[todo.pop()] & set(uses):
                if dep not in live:
                    live.add(dep)
                    todo.append(dep)
        warn_unused(self.path, [n for n in uses if n not in live], "input")
        warn_unused(self.path, [k for k in values if k not in used])

    def system(self, model: dict, name: str) -> System:
        coords = model.get("coordinates", [])
        if not isinstance(coords, list) or not all(isinstance(c, str) for c in coords):
            raise self.fail("model.coordinates", "must be a list of names")
        fams = self.tables("families")
        if not coords and not fams:
            raise self.fail("model.coordinates", "a model needs coordinates (or [[families]])")
        for i, c in enumerate(coords):
            check_name(c, self.where(f"model.coordinates[{i}]"))
        if len(set(coords)) != len(coords):
            raise self.fail("model.coordinates", "a coordinate is named twice")
        made = make_coordinates(" ".join(coords)) if coords else ()
        qs = [made] if len(coords) == 1 else list(made)
        system = System(qs, name=name) if qs else System(name=name)
        self.names.update(zip(coords, qs, strict=True))
        for i, fam in enumerate(fams):
            key = f"families[{i}]"
            self.keys(key, fam, {"name", "n", "first"}, {"name", "n"})
            fname = fam["name"]
            check_name(fname, self.where(f"{key}.name"))
            if fname in self.names or fname in self.families:
                raise self.fail(f"{key}.name", f"`{fname}` is declared twice")
            for k in ("n", "first"):
                v = fam.get(k, 0)
                if not isinstance(v, int) or isinstance(v, bool):
                    raise self.fail(f"{key}.{k}", "must be a whole number")
            try:
                f = system.add_family(fname, fam["n"], first=fam.get("first", 0))
            except ModelError as e:
                raise self.fail(key, str(e)) from None
            self.families[fname] = f
        return system

    def parameters(self, model: dict) -> dict[str, float]:
        params = self.table("model.parameters", model.get("parameters", {}))
        values = {}
        for k, v in params.items():
            where = f"model.parameters.{k}"
            check_name(k, self.where(where))
            if k in self.names or k in self.families:
                raise self.fail(where, f"`{k}` is already a coordinate, family or t")
            values[k] = parse_number(v, self.where(where))
            self.names[k] = sp.Symbol(k)
        return values

    def energies(self, system: System, model: dict) -> None:
        for kind in ("kinetic", "potential", "dissipation"):
            terms = model.get(kind, [])
            terms = [terms] if isinstance(terms, str) else terms
            if not isinstance(terms, list):
                raise self.fail(f"model.{kind}", "must be an expression or a list of them")
            for i, text in enumerate(terms):
                key = f"model.{kind}" + (f"[{i}]" if len(terms) > 1 else "")
                e = self.expr(key, text)
                add = {
                    "kinetic": system.add_kinetic_energy,
                    "potential": system.add_potential_energy,
                    "dissipation": system.add_dissipation,
                }[kind]
                self.call(key, add, e)

    def call(self, key: str, fn: Any, *args: Any, **kw: Any) -> Any:
        """A System method; its ModelError names this key of the file."""
        try:
            return fn(*args, **kw)
        except (ModelError, ExpressionError) as e:
            raise self.fail(key, str(e)) from None
        except ValueError as e:  # any other value problem of the pieces (a ConstraintError)
            raise self.fail(key, str(e)) from None

    def particles(self, system: System) -> None:
        for i, p in enumerate(self.tables("particles")):
            key = f"particles[{i}]"
            self.keys(key, p, {"mass", "position", "name", "over"}, {"mass", "position"})
            over, k = self.over(key, p)
            m = self.expr(f"{key}.mass", p["mass"], index=k)
            r = self.exprs(f"{key}.position", p["position"], index=k)
            self.call(key, system.add_particle, m, r, name=self.name_of(key, p), over=over)

    def bodies_(self, system: System) -> None:
        kinds = {"euler": EulerAngles, "quaternion": Quaternion, "mrp": MRP, "planar": PlanarAngle}
        for i, b in enumerate(self.tables("bodies")):
            key = f"bodies[{i}]"
            allowed = {"mass", "inertia", "position", "attitude", "coordinates", "sequence", "name"}
            if isinstance(b.get("attitude"), dict):  # attitude = { kind, coordinates, sequence }
                att_table = b["attitude"]
                self.keys(f"{key}.attitude", att_table, {"kind", "coordinates", "sequence"},
                          {"kind", "coordinates"})  # fmt: skip
                b = {**{k: v for k, v in b.items() if k != "attitude"}, **att_table}
                b["attitude"] = b.pop("kind")
            self.keys(key, b, allowed, {"mass", "inertia", "position", "attitude", "coordinates"})
            kind = b["attitude"]
            if kind not in kinds:
                raise self.fail(f"{key}.attitude", f"must be one of {', '.join(kinds)}")
            names = b["coordinates"]
            if not isinstance(names, list) or not all(isinstance(c, str) for c in names):
                raise self.fail(f"{key}.coordinates", "must be a list of coordinate names")
            qs = []
            for c in names:
                q = self.names.get(c)
                if q is None or q.is_Symbol:
                    raise self.fail(f"{key}.coordinates", f"`{c}` is not a declared coordinate")
                qs.append(q)
            try:
                if kind == "euler":
                    seq = b.get("sequence", "321")
                    if not isinstance(seq, str):
                        raise self.fail(f"{key}.sequence", 'must be a string such as "321"')
                    att = EulerAngles(qs, seq)
                else:
                    att = kinds[kind](qs)
            except ModelError as e:
                raise self.fail(key, str(e)) from None
            m = self.expr(f"{key}.mass", b["mass"])
            inertia = self.inertia(f"{key}.inertia", b["inertia"])
            r = self.exprs(f"{key}.position", b["position"])
            body = self.call(key, system.add_rigid_body, m, inertia, r, att, self.name_of(key, b))
            self.bodies[body.name] = body
            if body.constraint:
                self.constraints.append(body.constraint)

    def inertia(self, key: str, value: object) -> object:
        if isinstance(value, list) and value and all(isinstance(r, list) for r in value):
            if len(value) != 3 or any(len(r) != 3 for r in value):
                raise self.fail(key, "a matrix must be 3×3")
            return sp.Matrix(
                [
                    [self.expr(f"{key}[{i}][{j}]", v) for j, v in enumerate(r)]
                    for i, r in enumerate(value)
                ]
            )
        if isinstance(value, list):
            return self.exprs(key, value, sizes=(3,))
        return self.expr(key, value)

    def forces(self, system: System) -> None:
        for i, f in enumerate(self.tables("forces")):
            key = f"forces[{i}]"
            self.keys(key, f, {"force", "at", "name", "over"}, {"force", "at"})
            over, k = self.over(key, f)
            F = self.exprs(f"{key}.force", f["force"], index=k)
            at = self.exprs(f"{key}.at", f["at"], index=k)
            self.call(key, system.add_force, F, at, name=self.name_of(key, f), over=over)
        for i, g in enumerate(self.tables("generalized_forces")):
            key = f"generalized_forces[{i}]"
            self.keys(key, g, {"coordinate", "expr", "name"}, {"coordinate", "expr"})
            c = g["coordinate"]
            if not isinstance(c, str) or c not in self.names or self.names[c].is_Symbol:
                raise self.fail(f"{key}.coordinate", f"`{c}` is not a declared coordinate")
            e = self.expr(f"{key}.expr", g["expr"])
            self.call(
                key, system.add_generalized_force, self.names[c], e, name=self.name_of(key, g)
            )
        for i, tq in enumerate(self.tables("torques")):
            key = f"torques[{i}]"
            self.keys(key, tq, {"torque", "on", "frame", "name"}, {"torque", "on"})
            body = self.bodies.get(tq["on"]) if isinstance(tq["on"], str) else None
            if body is None:
                raise self.fail(
                    f"{key}.on",
                    f"must name a body of the file ({', '.join(self.bodies) or 'none'})",
                )
            val = tq["torque"]
            tau = (
                self.exprs(f"{key}.torque", val, sizes=(3,))
                if isinstance(val, list)
                else self.expr(f"{key}.torque", val)
            )
            frame = tq.get("frame", "inertial")
            self.call(key, system.add_torque, tau, on=body, frame=frame, name=self.name_of(key, tq))
        for kind in ("springs", "dampers"):
            for i, s in enumerate(self.tables(kind)):
                key = f"{kind}[{i}]"
                coef = "k" if kind == "springs" else "c"
                allowed = {coef, "between", "name"} | (
                    {"rest_length"} if kind == "springs" else set()
                )
                self.keys(key, s, allowed, {coef, "between"})
                pts = s["between"]
                if not isinstance(pts, list) or len(pts) != 2:
                    raise self.fail(f"{key}.between", "must be two points [[...], [...]]")
                p1, p2 = (self.exprs(f"{key}.between[{j}]", pts[j]) for j in range(2))
                value = self.expr(f"{key}.{coef}", s[coef])
                if kind == "springs":
                    rest = self.expr(f"{key}.rest_length", s.get("rest_length", 0))
                    self.call(
                        key,
                        system.add_spring,
                        value,
                        between=(p1, p2),
                        rest_length=rest,
                        name=self.name_of(key, s),
                    )
                else:
                    self.call(
                        key, system.add_damper, value, between=(p1, p2), name=self.name_of(key, s)
                    )

    def constraints_(self, system: System) -> None:
        for i, c in enumerate(self.tables("constraints")):
            key = f"constraints[{i}]"
            self.keys(key, c, {"name", "holonomic", "velocity", "over"})
            kinds = [k for k in ("holonomic", "velocity") if k in c]
            if len(kinds) != 1:
                raise self.fail(key, "needs exactly one of `holonomic` or `velocity`")
            over, k = self.over(key, c)
            e = self.expr(f"{key}.{kinds[0]}", c[kinds[0]], index=k)
            name = self.name_of(key, c) or f"constraint{len(self.constraints) + 1}"
            add = (
                system.add_holonomic_constraint
                if kinds[0] == "holonomic"
                else system.add_velocity_constraint
            )
            self.call(key, add, e, name, over=over)
            self.constraints.append(name)

    def contacts_(self, system: System) -> None:
        for i, c in enumerate(self.tables("contacts")):
            key = f"contacts[{i}]"
            self.keys(key, c, {"name", "gap", "restitution"}, {"gap"})
            gap = self.expr(f"{key}.gap", c["gap"])
            e = self.expr(f"{key}.restitution", c.get("restitution", 0))
            self.call(key, system.add_unilateral_constraint, gap, self.name_of(key, c), e)

    def events_(self, system: System) -> None:
        for i, ev in enumerate(self.tables("events")):
            key = f"events[{i}]"
            self.keys(key, ev, {"name", "condition", "direction", "terminal"}, {"condition"})
            cond = self.expr(f"{key}.condition", ev["condition"])
            direction, terminal = ev.get("direction", 0), ev.get("terminal", False)
            if isinstance(direction, bool) or direction not in (-1, 0, 1):
                raise self.fail(f"{key}.direction", "must be -1 (falling), 0 (both) or 1 (rising)")
            if not isinstance(terminal, bool | int) or (
                not isinstance(terminal, bool) and not 0 <= terminal <= 1_000_000
            ):
                raise self.fail(f"{key}.terminal", "must be true, false or a count from 0")
            name = self.name_of(key, ev)
            self.call(key, system.add_event, cond, name, direction=direction, terminal=terminal)

    def initial(self, system: System) -> tuple[np.ndarray, np.ndarray]:
        init = self.table("initial", self.data.get("initial", {}))
        self.keys("initial", init, {"q", "qd"})
        out = []
        index = {str(q.func): i for i, q in enumerate(system._ordinary)}
        for part in ("q", "qd"):
            vec = np.zeros(system.n)
            values = self.table(f"initial.{part}", init.get(part, {}))
            for name, v in values.items():
                key = f"initial.{part}.{name}"
                if name in index:
                    vec[index[name]] = parse_number(v, self.where(key))
                elif name in self.families:
                    fam = self.families[name]
                    seg = slice(fam.offset, fam.offset + fam.n)
                    if isinstance(v, list):
                        if len(v) != fam.n:
                            raise self.fail(
                                key, f"needs {fam.n} values (one per member), got {len(v)}"
                            )
                        vec[seg] = [
                            parse_number(x, self.where(f"{key}[{j}]")) for j, x in enumerate(v)
                        ]
                    else:
                        vec[seg] = parse_number(v, self.where(key))
                else:
                    raise self.fail(key, f"`{name}` is not a coordinate or family of the model")
            out.append(vec)
        return out[0], out[1]

    def simulate(self) -> dict[str, Any]:
        sim = self.table("simulate", self.data.get("simulate", {}))
        self.keys("simulate", sim, set(SIMULATE_KEYS))
        out: dict[str, Any] = {}
        for k, v in sim.items():
            kind = SIMULATE_KEYS[k]
            key = f"simulate.{k}"
            if kind is float:
                out[k] = parse_number(v, self.where(key))
                if k not in ("alpha", "beta", "rest_speed") and not out[k] > 0:
                    raise self.fail(key, f"must be positive, got {out[k]}")
            elif kind is bool:
                if not isinstance(v, bool):
                    raise self.fail(key, "must be true or false")
                out[k] = v
            elif kind is int:
                if not isinstance(v, int) or isinstance(v, bool) or not 2 <= v <= 1_000_000:
                    raise self.fail(key, "must be a whole number from 2 to 1000000")
                out[k] = v
            else:
                if not isinstance(v, str) or len(v) > 40:
                    raise self.fail(key, "must be a short string")
                out[k] = v
        if "t_end" in out and not math.isfinite(out["t_end"]):
            raise self.fail("simulate.t_end", "must be finite")
        return out
