"""Linearization of derived equations about an operating point (equilibrium or steady motion).

:class:`LinearForms` writes the equations of a :class:`pfaff.derive.equations.Derivation` in plain
symbols, E = M q̈ − (Q − h) − Aᵀλ, G = A q̈ + Ȧq̇ + ḃ, V = A q̇ + b and the holonomic f, and
differentiates them exactly by q, q̇ and the inputs (in SymEngine when the round trip is exact,
:mod:`pfaff.derive.engine`; else in SymPy). :func:`linearize` checks an operating point given as a
dict (consistent with every constraint, accelerations of the kept rates zero) and hands the
matrices at it to :func:`pfaff.numeric.linearization.reduce_linear`: as floats when every value is
a number, as SymPy matrices otherwise. :class:`CompiledLinearizer` (:func:`linearizer_for`) generates the same
matrices once into code of (t, q, q̇, q̈, λ, parameters) for :meth:`pfaff.NumericModel.linearize`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Sequence
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
import symengine
import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ConstraintError, ModelError, ModelTypeError, StateError
from pfaff.core.symbols import as_expr, is_coordinate_like, speed, t
from pfaff.numeric.linearization import (
    NUMPY,
    TOL,
    Linearization,
    OperatingMatrices,
    complement,
    operating_solve,
    reduce_linear,
)
from pfaff.numeric.linearizer import check_steady
from pfaff.numeric.redundant import independent_rows

if TYPE_CHECKING:
    from pfaff.derive.equations import Derivation


class SympyOps:
    """The matrix operations of :func:`reduce_linear` on SymPy matrices (symbolic values)."""

    @staticmethod
    def zeros(rows: int, cols: int) -> sp.Matrix:
        return sp.zeros(rows, cols)

    @staticmethod
    def take(a: sp.Matrix, rows: Sequence[int], cols: Sequence[int]) -> sp.Matrix:
        return sp.Matrix(a).extract(list(rows), list(cols))

    @staticmethod
    def put(a: sp.Matrix, rows: Sequence[int], cols: Sequence[int], value: Any) -> None:
        for i, r in enumerate(rows):
            for j, c in enumerate(cols):
                a[r, c] = value[i, j]

    @staticmethod
    def hstack(*blocks: sp.Matrix) -> sp.Matrix:
        return sp.Matrix.hstack(*blocks)

    @staticmethod
    def vstack(*blocks: sp.Matrix) -> sp.Matrix:
        return sp.Matrix.vstack(*blocks)

    @staticmethod
    def eye(k: int) -> sp.Matrix:
        return sp.eye(k)

    @staticmethod
    def solve(a: sp.Matrix, b: sp.Matrix, what: str) -> sp.Matrix:
        if a.shape[0] == 0:
            return sp.zeros(0, b.shape[1])
        a = a.applyfunc(sp.cancel)
        if sp.simplify(a.det(method="berkowitz")) == 0:
            raise ConstraintError(f"{what} is singular at the operating point")
        return a.LUsolve(b, iszerofunc=lambda e: sp.simplify(e) == 0).applyfunc(sp.cancel)

    @staticmethod
    def independent(a: sp.Matrix) -> list[int] | None:
        """A maximal set of independent rows (the pivots of rref(aᵀ)), None when all are."""
        if all(e.is_number for e in a):
            rows = independent_rows(np.array(a.evalf(), dtype=float))
            return None if rows is None else rows.tolist()
        pivots = list(a.T.rref(simplify=True)[1])
        return None if len(pivots) == a.shape[0] else pivots

    @staticmethod
    def spread(a: sp.Matrix, keep: Sequence[int], lam: sp.Matrix) -> sp.Matrix:
        """δλ over all rows: the minimum-norm one where ``a`` is numeric (its pseudo-inverse),
        else the kept rows' δλ and 0 on the others (only Aᵀδλ is determined there)."""
        if all(e.is_number for e in a):
            A = np.array(a.evalf(), dtype=float)
            P = np.linalg.lstsq(A.T, A[list(keep)].T, rcond=1e-9)[0]
            return sp.Matrix(P) * lam
        out = sp.zeros(a.shape[0], lam.shape[1])
        for k, row in enumerate(keep):
            out[row, :] = lam[k, :]
        return out

    @staticmethod
    def finish(a: sp.Matrix) -> sp.Matrix:
        return sp.ImmutableMatrix(a.applyfunc(lambda e: sp.simplify(sp.cancel(e))))


SYMPY = SympyOps()


# --------------------------------------------------------------------------- the forms
class _Back:
    """SymEngine results back to SymPy with the parameters' own symbols (their assumptions)."""

    def __init__(self, params: Sequence[sp.Symbol]) -> None:
        self.restore = {sp.Symbol(p.name): p for p in params if sp.Symbol(p.name) != p}

    @staticmethod
    def to(e: object) -> symengine.Basic:
        return symengine.sympify(e)

    def back(self, e: object) -> sp.Expr:
        x = sp.sympify(e)
        return x.xreplace(self.restore) if self.restore else x


def _engine_forms(eom: Derivation, args: list) -> tuple | None:
    """(M, A, F, bias, b, f) in SymEngine, assembled from the templates' local forms by the
    fused kernel's assembly (:func:`pfaff.derive.fused._engine_parts`), in the names of ``args``
    (t, q, q̇, parameters); None where it does not apply (a function SymEngine lacks)."""
    from pfaff.derive.fused import _engine_parts

    n, m = eom.n, eom.m
    try:
        parts = _engine_parts(eom, args)
    except Exception:  # an assembly this module cannot take: SymPy's then
        return None
    if parts is None:
        return None
    mass, acon, exprs, _ = parts
    zero = symengine.Integer(0)
    M = [[zero] * n for _ in range(n)]
    for (i, j), e in zip(mass, exprs, strict=False):
        M[i][j] = M[j][i] = e
    k = len(mass)
    A = [[zero] * n for _ in range(m)]
    for (i, j), e in zip(acon, exprs[k:], strict=False):
        A[i][j] = e
    k += len(acon)
    F = exprs[k : k + n]
    bias = [-e for e in exprs[k + n : k + n + m]]
    b = exprs[k + n + m : k + n + 2 * m]
    f = exprs[k + n + 2 * m : k + n + 3 * m]
    return M, A, F, bias, b, f


def _sympy_forms(eom: Derivation, rule: dict) -> tuple:
    """(M, A, F, bias, b, f) in SymPy, from the derivation's numeric parts renamed by ``rule``."""
    n, m = eom.n, eom.m
    parts = eom.numeric_parts
    con = eom._constraint_entries

    def r(e: object) -> sp.Expr:
        return sp.sympify(e).xreplace(rule)

    M = [[r(parts.mass.get((i, j), 0)) for j in range(n)] for i in range(n)]
    A = [[r(con["A"].get((i, j), 0)) for j in range(n)] for i in range(m)]
    F = [r(e) for e in parts.forcing]
    fs = [sp.S.Zero if e is None else r(e) for e in con["f"]]
    return M, A, F, [r(e) for e in con["bias"]], [r(e) for e in con["b"]], fs


class LinearForms:
    """E, G, V and f of a derivation in plain symbols, with their derivatives.

    E = M q̈ − F − Aᵀλ (F = Q − h), G = A q̈ + Ȧq̇ + ḃ, V = A q̇ + b, f the holonomic rows; in
    SymEngine (assembled from the templates' local forms) when the round trip is exact, else in
    SymPy.

    Parameters
    ----------
    eom : Derivation
    inputs : sequence
        Parameters (Symbols) and functions of time (``F(t)``) differentiated as inputs.

    Attributes
    ----------
    q, qd, qdd, lam, u : list of Symbol
        The plain symbols of q, q̇, q̈, λ and the inputs (a parameter input is its own symbol).
    params : list of Symbol
        The parameters that are not inputs, in the derivation's order.
    """

    def __init__(self, eom: Derivation, inputs: Sequence = ()) -> None:
        n, m = eom.n, eom.m
        self.n, self.m, self.inputs = n, m, list(inputs)
        self.q = [sp.Symbol(f"_lq{i}") for i in range(n)]
        self.qd = [sp.Symbol(f"_lqd{i}") for i in range(n)]
        self.qdd = [sp.Symbol(f"_lqdd{i}") for i in range(n)]
        self.lam = [sp.Symbol(f"_llam{i}") for i in range(m)]
        self.u = [
            u if isinstance(u, sp.Symbol) else sp.Symbol(f"_lu{k}") for k, u in enumerate(inputs)
        ]
        self.params = [p for p in eom.parameters if p not in set(self.u)]
        self.hol = [i for i, f in enumerate(eom.holonomic_constraints) if f is not None]
        self.calls: dict[str, int] = {}
        funcs = any(not isinstance(u, sp.Symbol) for u in inputs)
        forms = None if funcs else _engine_forms(eom, [t, *self.q, *self.qd, *eom.parameters])
        if forms is not None:
            self.alg: Any = _Back(eom.parameters)
        else:
            self.alg = None
            rule: dict = {}
            for i, q in enumerate(eom.coordinates):
                rule[speed(q)] = self.qd[i]
                rule[q] = self.q[i]
            rule.update({u: s for u, s in zip(inputs, self.u, strict=True) if u != s})
            forms = _sympy_forms(eom, rule)
            leftover = {a for row in forms for e in row for a in _atoms(e) if a.has(t) and a != t}
            if leftover:
                raise ModelError(
                    "the equations depend on functions of time that are neither coordinates "
                    f"nor inputs: {', '.join(sorted(map(str, leftover)))}; name them in `inputs`"
                )
        M, A, F, bias, b, f = forms
        qdd, lam, qd = (list(map(self._sym, v)) for v in (self.qdd, self.lam, self.qd))
        self.M, self.A = M, A
        self.E = [
            sum((M[i][j] * qdd[j] for j in range(n)), -F[i])
            - sum((A[k][i] * lam[k] for k in range(m)), 0)
            for i in range(n)
        ]
        self.G = [sum((A[k][j] * qdd[j] for j in range(n)), bias[k]) for k in range(m)]
        self.V = [sum((A[k][j] * qd[j] for j in range(n)), b[k]) for k in range(m)]
        self.f = [f[k] for k in self.hol]

    def __getstate__(self) -> dict:
        """The forms without what is made from them (derivatives, numeric functions)."""
        return {k: v for k, v in self.__dict__.items() if k not in ("jacobians", "_fns")}

    def _sym(self, s: sp.Symbol) -> Any:
        return symengine.Symbol(s.name) if self.alg is not None else s

    @cached_property
    def args(self) -> list:
        """Arguments of the numeric functions: t, q, q̇, q̈, λ, u, parameters (not inputs)."""
        syms = [t, *self.q, *self.qd, *self.qdd, *self.lam, *self.u, *self.params]
        return [self._sym(s) for s in syms]

    def _jac(self, exprs: list, wrt: list) -> list[list]:
        vs = [self._sym(s) for s in wrt]
        out = []
        for e in exprs:
            free = e.free_symbols if hasattr(e, "free_symbols") else set()
            out.append([e.diff(v) if v in free else 0 for v in vs])
        return out

    @cached_property
    def jacobians(self) -> dict[str, list[list]]:
        """E_q, E_qd, E_u, G_q, G_qd, G_u, V_q, V_u as nested lists of expressions."""
        out = {}
        for name, exprs in (("E", self.E), ("G", self.G), ("V", self.V)):
            out[f"{name}_q"] = self._jac(exprs, self.q)
            out[f"{name}_u"] = self._jac(exprs, self.u)
            if name != "V":
                out[f"{name}_qd"] = self._jac(exprs, self.qd)
        return out

    # ------------------------------------------------------------------ numbers
    def _shapes(self) -> dict[str, tuple[int, int]]:
        n, m, r = self.n, self.m, len(self.u)
        return {
            "M": (n, n), "A": (m, n), "E": (n, 1), "G": (m, 1), "V": (m, 1),
            "f": (len(self.hol), 1), "E_q": (n, n), "E_qd": (n, n), "E_u": (n, r),
            "G_q": (m, n), "G_qd": (m, n), "G_u": (m, r), "V_q": (m, n), "V_u": (m, r),
        }  # fmt: skip

    def _lists(self, which: str) -> dict[str, list[list]]:
        if which == "values":
            col = lambda v: [[e] for e in v]  # noqa: E731
            return {"M": self.M, "A": self.A, "E": col(self.E), "G": col(self.G),
                    "V": col(self.V), "f": col(self.f)}  # fmt: skip
        return self.jacobians

    def _unflatten(self, names: list[str], vals: np.ndarray) -> dict[str, np.ndarray]:
        out, k = {}, 0
        for name in names:
            r, c = self._shapes()[name]
            out[name] = vals[k : k + r * c].reshape(r, c)
            k += r * c
        return out

    LAMBDIFY_AFTER = 20  # evaluations by substitution before the lambdified function is made

    def numbers(self, which: str, x: Sequence[float]) -> dict[str, np.ndarray]:
        """The matrices of ``which`` (``"values"``: M, A, E, G, V, f; or ``"jacobians"``) at the
        arguments ``x`` (floats, in the order of :attr:`args`).

        The first few evaluations substitute the numbers (SymEngine: 0.1 s on the bicycle);
        then the expressions are lambdified once (6 s on the bicycle, then 5 ms a call): a
        sweep (:func:`pfaff.root_locus`) gains."""
        lists = self._lists(which)
        names = list(lists)
        flat = [e for k in names for row in lists[k] for e in row]
        self.calls[which] = self.calls.get(which, 0) + 1
        fns = self.__dict__.setdefault("_fns", {})
        if which not in fns and self.alg is not None and self.calls[which] <= self.LAMBDIFY_AFTER:
            rule = {a: float(v) for a, v in zip(self.args, x, strict=True)}
            vals = [float(symengine.sympify(e).subs(rule)) for e in flat]
            return self._unflatten(names, np.array(vals, dtype=float))
        if which not in fns:
            if self.alg is not None:
                fns[which] = symengine.Lambdify(self.args, flat, cse=True, real=True)
            else:
                fns[which] = sp.lambdify(self.args, flat, modules="numpy", cse=True)
        fn = fns[which]
        vals = fn(np.asarray(x, dtype=float)) if self.alg is not None else fn(*x)
        return self._unflatten(names, np.asarray(vals, dtype=float).ravel())

    def symbolic(self, which: str, subs: dict) -> dict[str, sp.Matrix]:
        """The matrices of ``which`` with ``subs`` (plain symbol -> SymPy value) substituted."""
        shapes = self._shapes()
        if self.alg is None:
            rule = {k: sp.sympify(v) for k, v in subs.items()}

            def value(e: Any) -> sp.Expr:
                return sp.sympify(e).xreplace(rule)
        else:
            rule = {self._sym(k): self.alg.to(v) for k, v in subs.items()}

            def value(e: Any) -> sp.Expr:
                return self.alg.back(symengine.sympify(e).subs(rule))

        return {
            name: sp.Matrix(*shapes[name], [value(e) for row in rows for e in row])
            for name, rows in self._lists(which).items()
        }


def _atoms(e: sp.Expr) -> set:
    return e.atoms(AppliedUndef, sp.Derivative) if isinstance(e, sp.Basic) else set()


# --------------------------------------------------------------------------- the arguments
def _coordinate_index(eom: Derivation, key: object, arg: str) -> int:
    names = {str(q.func): i for i, q in enumerate(eom.coordinates)}
    if isinstance(key, str):
        if key in names:
            return names[key]
    elif isinstance(key, sp.Derivative) and arg == "independent_speeds":
        if key.args[1:] == ((t, 1),) and key.expr in eom.coordinates:
            return eom.coordinates.index(key.expr)
    elif isinstance(key, sp.Basic):
        if key in eom.coordinates:
            return eom.coordinates.index(key)
    else:
        raise ModelTypeError(
            f"`{arg}` must list coordinates (functions of pfaff.t) or their names; got "
            f"{type(key).__name__} {key!r:.60}"
        )
    raise ModelError(
        f"`{arg}`: {key!s:.60} is not a coordinate{' or its rate' * (arg != 'independent')} of "
        f"this system (coordinates: {', '.join(names)})"
    )


def coordinate_list(eom: Derivation, keys: object, arg: str) -> list[int]:
    """Indices of the coordinates (or rates) ``keys`` names; each at most once."""
    if isinstance(keys, str | sp.Basic):
        keys = [keys]
    try:
        keys = list(keys)  # type: ignore[call-overload]
    except TypeError:
        raise ModelTypeError(f"`{arg}` must be a list of coordinates; got {keys!r:.60}") from None
    idx = [_coordinate_index(eom, k, arg) for k in keys]
    twice = sorted({i for i in idx if idx.count(i) > 1})
    if twice:
        names = ", ".join(f"`{eom.coordinates[i].func}`" for i in twice)
        raise ModelError(f"`{arg}` names {names} twice")
    return idx


def input_list(eom: Derivation, inputs: object) -> list:
    """The inputs as SymPy objects: parameters (by Symbol or name) or functions of time."""
    if isinstance(inputs, str | sp.Basic):
        inputs = [inputs]
    by_name = {p.name: p for p in eom.parameters}
    out: list = []
    for u in inputs:  # type: ignore[union-attr]
        if isinstance(u, str):
            if u not in by_name:
                raise ModelError(
                    f"`inputs`: {u!r:.60} is not a parameter of the model "
                    f"(parameters: {', '.join(by_name) or 'none'})"
                )
            u = by_name[u]
        elif isinstance(u, sp.Symbol):
            if u not in eom.parameters and u.name in by_name:
                u = by_name[u.name]
            if u not in eom.parameters:
                raise ModelError(f"`inputs`: {u} is not a parameter of the model")
        elif is_coordinate_like(u):
            if u in eom.coordinates:
                raise ModelError(f"`inputs`: {u} is a coordinate, not an input")
        else:
            raise ModelTypeError(
                f"`inputs` must list parameters (Symbols or names) or functions of time; got "
                f"{type(u).__name__} {u!r:.60}"
            )
        if u in out:
            raise ModelError(f"`inputs` names {u} twice")
        out.append(u)
    return out


class OperatingPoint:
    """The values of ``op_point``: q (all), the rates given, parameters, inputs and t."""

    def __init__(self, eom: Derivation, op_point: object, inputs: list) -> None:
        if not isinstance(op_point, dict):
            raise ModelTypeError(f"`op_point` must be a dict; got {type(op_point).__name__}")
        coords = list(eom.coordinates)
        params = {p.name: p for p in eom.parameters}
        funcs = {str(u.func): u for u in inputs if not isinstance(u, sp.Symbol)}
        self.q: dict[int, sp.Expr] = {}
        self.qd: dict[int, sp.Expr] = {}
        self.params: dict[sp.Symbol, sp.Expr] = {}
        self.u: dict = {}
        self.t: sp.Expr = sp.S.Zero
        for key, value in op_point.items():
            target = self._target(eom, key, coords, params, funcs)
            v = as_expr(value, f"`op_point[{key!s:.40}]`")
            kind, k = target
            slot = {"q": self.q, "qd": self.qd, "p": self.params, "u": self.u}.get(kind)
            if slot is None:
                self.t = v
                continue
            if k in slot and slot[k] != v:  # by name and by symbol, say: the same value only
                raise ModelError(f"`op_point` gives {key!s:.40} twice, {slot[k]} and {v}")
            slot[k] = v
        missing = [str(coords[i].func) for i in range(len(coords)) if i not in self.q]
        if missing:
            raise ModelError(f"`op_point` gives no value for the coordinates {', '.join(missing)}")
        for u in inputs:  # an input is a parameter: its value, if given, is the input's
            if u in self.params:
                self.u[u] = self.params.pop(u)

    @staticmethod
    def _target(eom, key, coords, params, funcs) -> tuple[str, object]:
        if isinstance(key, str):
            names = {str(q.func): i for i, q in enumerate(coords)}
            if key in names:
                return "q", names[key]
            if key in params:
                return "p", params[key]
            if key in funcs:
                return "u", funcs[key]
        elif isinstance(key, sp.Derivative):
            if key.args[1:] == ((t, 1),) and key.expr in coords:
                return "qd", coords.index(key.expr)
        elif key == t:
            return "t", None
        elif isinstance(key, sp.Symbol):
            if key in eom.parameters or key.name in params:
                return "p", params[key.name]
        elif isinstance(key, AppliedUndef):
            if key in coords:
                return "q", coords.index(key)
            if str(key.func) in funcs and funcs[str(key.func)] == key:
                return "u", key
        elif not isinstance(key, sp.Basic):
            raise ModelTypeError(
                "`op_point` keys must be coordinates, rates (q.diff(pfaff.t)), parameters, "
                f"inputs or their names; got {type(key).__name__} {key!r:.60}"
            )
        raise ModelError(
            f"`op_point`: {key!s:.60} is not a coordinate, rate, parameter or input of the model"
        )


# --------------------------------------------------------------------------- the linearization
def _is_number(e: object) -> bool:
    return isinstance(e, int | float | np.floating) or (isinstance(e, sp.Basic) and e.is_number)


def _too_big(e: object, tol: float) -> bool:
    """Whether a residual is not zero: beyond ``tol`` (numbers) or not simplified to 0."""
    if _is_number(e):
        v = complex(e)
        return not math.isfinite(abs(v)) or abs(v) > tol
    return sp.simplify(e) != 0


def _max_abs(a: Any) -> float:
    vals = [abs(complex(e)) for e in np.ravel(np.asarray(a, dtype=object)) if _is_number(e)]
    return max(vals, default=0.0)


class Evaluator:
    """The forms' matrices at a point: floats (every value numeric) or SymPy (some symbolic)."""

    def __init__(self, forms: LinearForms, t0: Any, q0: list, u0: list, params: dict) -> None:
        self.forms = forms
        values = [t0, *q0, *u0, *(params.get(p, p) for p in forms.params)]
        self.numeric = all(_is_number(v) for v in values)
        self.ops = NUMPY if self.numeric else SYMPY
        self.t0, self.q0, self.u0 = t0, q0, u0
        self.params = params
        if self.numeric:
            self.p = [float(params[p]) for p in forms.params]

    def __call__(self, which: str, qd: list, qdd: list, lam: list) -> dict:
        f = self.forms
        if self.numeric:
            x = [self.t0, *self.q0, *qd, *qdd, *lam, *self.u0, *self.p]
            return f.numbers(which, [float(v) for v in x])
        subs = dict(zip(f.q, self.q0, strict=True)) | {t: self.t0}
        subs |= dict(zip(f.qd, qd, strict=True)) | dict(zip(f.qdd, qdd, strict=True))
        subs |= dict(zip(f.lam, lam, strict=True)) | dict(zip(f.u, self.u0, strict=True))
        subs |= {p: v for p, v in self.params.items() if p in set(f.params)}
        return f.symbolic(which, subs)


def linear_forms(eom: Derivation, inputs: Sequence) -> LinearForms:
    """The :class:`LinearForms` of ``eom`` with these inputs (made once per derivation)."""
    cache = eom.__dict__.setdefault("_linear_forms", {})
    key = tuple(inputs)
    if key not in cache:
        cache[key] = LinearForms(eom, key)
    return cache[key]


def linearize(
    eom: Derivation,
    op_point: dict,
    independent: object,
    independent_speeds: object = None,
    inputs: object = (),
) -> Linearization:
    """Linearize ``eom`` about ``op_point`` (see :meth:`pfaff.EquationsOfMotion.linearize`)."""
    ind = coordinate_list(eom, independent, "independent")
    spd = (
        ind
        if independent_speeds is None
        else coordinate_list(eom, independent_speeds, "independent_speeds")
    )
    ins = input_list(eom, inputs)
    point = OperatingPoint(eom, op_point, ins)
    forms = linear_forms(eom, ins)
    q0 = [point.q[i] for i in range(eom.n)]
    u0 = [point.u.get(u, sp.S.Zero) for u in ins]
    ev = Evaluator(forms, point.t, q0, u0, point.params)
    conv = float if ev.numeric else (lambda e: e)
    qd0 = [point.qd.get(i, sp.S.Zero) for i in range(eom.n)]
    qd0 = _dependent_rates(eom, ev, [conv(e) for e in qd0], point, spd)
    return linearize_at(ev, eom, qd0, ind, spd, ins)


def _dependent_rates(eom: Derivation, ev: Evaluator, qd: list, point, spd: list[int]) -> list:
    """Rates not given and not kept: solved from the velocity constraints."""
    n, m = eom.n, eom.m
    unknown = [j for j in complement(n, spd) if j not in point.qd]
    if not unknown or not m:
        return qd
    vals = ev("values", qd, [0] * n, [0] * m)
    Au = ev.ops.take(vals["A"], range(m), unknown)
    if ev.numeric:
        x = np.linalg.lstsq(Au, -vals["V"][:, 0], rcond=None)[0]
    else:
        sol, free = sp.Matrix(Au).gauss_jordan_solve(-sp.Matrix(vals["V"]))
        x = list(sol.xreplace(dict.fromkeys(free, 0)))
    qd = list(qd)
    for j, v in zip(unknown, x, strict=True):
        qd[j] = float(v) if ev.numeric else sp.simplify(v)
    return qd


def _check_constraints(eom: Derivation, vals: dict, q0: list, qd: list) -> None:
    names = list(eom.constraint_names)
    hol = [i for i, f in enumerate(eom.holonomic_constraints) if f is not None]
    tol_f = TOL * (1.0 + _max_abs(q0))
    tol_v = TOL * (1.0 + _max_abs(qd)) * (1.0 + _max_abs(vals["A"]))
    bad = [
        f"`{names[i]}`: f = {vals['f'][k, 0]}"
        for k, i in enumerate(hol)
        if _too_big(vals["f"][k, 0], tol_f)
    ]
    bad += [
        f"`{names[i]}`: A q̇ + b = {vals['V'][i, 0]}"
        for i in range(eom.m)
        if _too_big(vals["V"][i, 0], tol_v)
    ]
    if bad:
        raise ConstraintError(
            "the operating point violates the constraints (give values that satisfy them): "
            + "; ".join(bad)
        )


def linearize_at(
    ev: Evaluator, eom: Derivation, qd0: list, ind: list[int], spd: list[int], ins: list
) -> Linearization:
    """The checks and the reduction at a complete point (q₀, q̇₀); see :func:`linearize`."""
    n, m, ops = eom.n, eom.m, ev.ops
    names = [str(q.func) for q in eom.coordinates]
    vals = ev("values", qd0, [0] * n, [0] * m)
    _check_constraints(eom, vals, ev.q0, qd0)
    M, A = vals["M"], vals["A"]
    sol = operating_solve(ops, M, A, vals["E"], vals["G"])
    qdd0 = [sol[i, 0] for i in range(n)]
    lam0 = [sol[n + i, 0] for i in range(m)]
    scale = TOL * (1.0 + _max_abs(vals["E"]) / max(_max_abs(M), 1e-300))
    moving = [f"q̈ of `{names[j]}` = {qdd0[j]}" for j in spd if _too_big(qdd0[j], scale)]
    if moving:
        raise StateError(
            "the operating point is not an equilibrium or steady motion: the kept rates "
            "accelerate (" + "; ".join(moving) + ")"
        )
    jac = ev("jacobians", qd0, qdd0, lam0)
    mats = OperatingMatrices(M, A, list(ev.forms.hol), **jac)
    Amat, B, C, D = reduce_linear(mats, ind, spd, names, ops)
    if ev.numeric:
        check_steady(Amat, ind, qd0, names)
    states = [eom.coordinates[i] for i in ind] + [speed(eom.coordinates[i]) for i in spd]
    lam = np.array(lam0, dtype=float) if ev.numeric else sp.ImmutableMatrix(lam0)
    return Linearization(Amat, B, states, ins, (C, D), lam)


class _Kernel:
    """:class:`pfaff.numeric.linearizer.LinearizationKernel` of a :class:`CompiledLinearizer`:
    its generated functions for these inputs (shared with the factory's other kernels)."""

    def __init__(self, factory: CompiledLinearizer, inputs: tuple[int, ...]) -> None:
        self._factory, self._inputs = factory, inputs
        forms = factory.forms
        self._values = factory.function("values")
        self._state = factory.function("state")
        self._input = factory.function(inputs) if inputs else None
        shapes = forms._shapes()
        n, m, r = forms.n, forms.m, len(inputs)
        shapes.update({"E_u": (n, r), "G_u": (m, r), "V_u": (m, r)})
        self._layout = {
            which: [(k, shapes[k]) for k in keys]
            for which, keys in (("values", VALUES), ("state", STATE), ("input", INPUT))
        }

    @staticmethod
    def _unflatten(layout: list, flat: np.ndarray) -> dict[str, np.ndarray]:
        out, k = {}, 0
        for name, (r, c) in layout:
            out[name] = flat[k : k + r * c].reshape(r, c)
            k += r * c
        return out

    def values(self, x: np.ndarray) -> dict[str, np.ndarray]:
        return self._unflatten(self._layout["values"], self._values(x))

    def jacobians(self, x: np.ndarray) -> dict[str, np.ndarray]:
        out = self._unflatten(self._layout["state"], self._state(x))
        if self._input is not None:
            out |= self._unflatten(self._layout["input"], self._input(x))
        else:
            out |= self._unflatten(self._layout["input"], np.zeros(0))
        return out


VALUES = ("M", "A", "E", "G", "V", "f")
STATE = ("E_q", "E_qd", "G_q", "G_qd", "V_q")
INPUT = ("E_u", "G_u", "V_u")


class CompiledLinearizer:
    """The :class:`pfaff.numeric.linearizer.LinearizerFactory` of a derivation: what
    :meth:`pfaff.NumericModel.linearize` evaluates.

    On the first request the equations' :class:`LinearForms` (no inputs: every parameter is an
    argument) are differentiated by q and q̇ once, and by the parameters asked for as inputs once
    per such set, and generated into functions of x = (t, q, q̇, q̈, λ, p) (SymEngine's
    ``Lambdify``: machine code through LLVM where this SymEngine has it, with common
    subexpressions shared); later calls are numeric only, for any parameter values (models
    made by ``with_parameters`` share the factory) and input values.

    Pickling keeps the forms (SymEngine or SymPy expressions) and drops the derivation, the
    derivatives and the generated functions: they are made again on first use after unpickling.

    Parameters
    ----------
    eom : Derivation

    Attributes
    ----------
    coordinates, speeds : tuple, length n
        The coordinates q(t) and their rates q̇(t) (:attr:`Linearization.states`).
    parameters : tuple of Symbol
        The derivation's parameters, in the compiled model's order.
    holonomic_rows : list of int
        The constraint rows with a holonomic f.

    Examples
    --------
    >>> import numpy as np, pfaff
    >>> eom = pfaff.models.pendulum().equations()
    >>> factory = linearizer_for(eom)
    >>> [p.name for p in factory.parameters]
    ['L', 'g', 'm']
    >>> x = np.array([0.0, 0.0, 0.0, 0.0, 2.0, 9.81, 1.0])  # t, q, q̇, q̈, (no λ), L, g, m
    >>> factory.kernel(()).jacobians(x)["E_q"]  # ∂(m L² θ̈ + m g L sin θ)/∂θ = m g L
    array([[19.62]])
    """

    def __init__(self, eom: Derivation) -> None:
        self._eom: Derivation | None = eom
        self.coordinates = tuple(eom.coordinates)
        self.speeds = tuple(speed(c) for c in eom.coordinates)
        self.parameters = tuple(eom.parameters)
        # (the flags, not the constraint expressions: nothing is assembled before the first call)
        self.holonomic_rows = [i for i, h in enumerate(eom.holonomic) if h]
        self._forms: LinearForms | None = None
        self._fns: dict = {}
        self._kernels: dict[tuple[int, ...], _Kernel] = {}

    @property
    def forms(self) -> LinearForms:
        """The :class:`LinearForms` without inputs (shared with the derivation's own)."""
        if self._forms is None:
            assert self._eom is not None
            self._forms = linear_forms(self._eom, ())
        return self._forms

    def kernel(self, inputs: tuple[int, ...]) -> _Kernel:
        """The kernel whose ``*_u`` Jacobians are by the parameters of indices ``inputs``."""
        k = self._kernels.get(inputs)
        if k is None:
            k = self._kernels[inputs] = _Kernel(self, inputs)
        return k

    def function(self, which: str | tuple[int, ...]) -> Callable[[np.ndarray], np.ndarray]:
        """The generated function of ``"values"``, ``"state"`` (the Jacobians by q and q̇) or
        a tuple of parameter indices (the Jacobians by them), made once."""
        fn = self._fns.get(which)
        if fn is None:
            fn = self._fns[which] = _generate(self.forms, self._exprs(which))
        return fn

    def generated(
        self, key: Hashable, exprs: Callable[[LinearForms], list]
    ) -> Callable[[np.ndarray], np.ndarray]:
        """A function of the same x generated once from ``exprs(self.forms)`` and kept under
        ``key``: the hook other kernels of these forms use (the variational equations,
        :mod:`pfaff.derive.variational`)."""
        fn = self._fns.get(key)
        if fn is None:
            fn = self._fns[key] = _generate(self.forms, exprs(self.forms))
        return fn

    def _exprs(self, which: str | tuple[int, ...]) -> list:
        f = self.forms
        if which == "values":
            lists = f._lists("values")
            return [e for k in VALUES for row in lists[k] for e in row]
        if which == "state":
            jac = f.jacobians
            return [e for k in STATE for row in jac[k] for e in row]
        params = [f.params[i] for i in which]
        jac = [f._jac(exprs, params) for exprs in (f.E, f.G, f.V)]
        return [e for rows in jac for row in rows for e in row]

    def __getstate__(self) -> dict:
        forms = self.forms
        return {
            **self.__dict__,
            "_eom": None,
            "_forms": forms,
            "_fns": {},
            "_kernels": {},
        }


def _generate(forms: LinearForms, exprs: list) -> Callable[[np.ndarray], np.ndarray]:
    """``exprs`` as a function of the flat argument array of ``forms.args`` returning a flat
    array: SymEngine's ``Lambdify`` (LLVM where available, without optimization passes: they
    cost more than they gain once), or SymPy's ``lambdify`` for forms SymEngine cannot take."""
    if not exprs:
        return _empty
    if forms.alg is not None:
        try:
            return symengine.Lambdify(
                forms.args, exprs, cse=True, real=True, backend="llvm", opt_level=0
            )
        except (ValueError, RuntimeError, TypeError):  # no LLVM in this SymEngine
            return symengine.Lambdify(forms.args, exprs, cse=True, real=True)
    fn = sp.lambdify(forms.args, exprs, modules="numpy", cse=True, docstring_limit=0)
    return lambda x: np.asarray(fn(*x), dtype=float)


def _empty(x: np.ndarray) -> np.ndarray:
    return np.zeros(0)


def linearizer_for(eom: Derivation) -> CompiledLinearizer:
    """The linearizer factory a compiled model of ``eom`` holds (nothing is derived yet).

    Examples
    --------
    >>> import pfaff
    >>> linearizer_for(pfaff.models.pendulum().equations()).holonomic_rows
    []
    """
    return CompiledLinearizer(eom)
