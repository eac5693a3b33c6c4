"""Time, generalized coordinates and the internal placeholder symbols.

Coordinates are what SymPy's ``dynamicsymbols`` makes: undefined functions of :data:`t`, the
symbol ``Symbol("t")`` that is SymPy's ``dynamicsymbols._t``, so positions built with
:mod:`sympy.physics.vector` frames and points can be handed to pfaff unchanged. They are made
here with :func:`sympy.symbols` directly: importing :mod:`sympy.physics` would load its units
package with pfaff (a tenth of ``import pfaff``).
"""

from __future__ import annotations

import re
import sys
from collections.abc import Iterable
from functools import cache

import sympy as sp
from sympy.core.function import AppliedUndef

from pfaff.core.errors import ModelError, ModelTypeError

t: sp.Symbol = sp.Symbol("t")
"""The time symbol, equal to ``sympy.physics.vector.dynamicsymbols._t`` (the plain symbol
``t``, so expressions of either are the same expressions)."""


_RESERVED = re.compile(r"_f?qd?[0-9]+")  # local placeholders of templates and fused code
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(:[0-9]+)?")  # a name, or a range name1:N


def coordinates(names: str) -> sp.Function | tuple[sp.Function, ...]:
    """Create generalized coordinates as functions of :data:`pfaff.t`.

    Parameters
    ----------
    names : str
        Names in the syntax of :func:`sympy.symbols`, ranges included (``"x theta1:65"``).

    Returns
    -------
    Function or tuple of Function
        One coordinate for a single name, else a tuple, each an applied function ``q(t)``.

    Examples
    --------
    >>> import pfaff
    >>> x, th = pfaff.coordinates("x theta")
    >>> x.args == (pfaff.t,)
    True
    >>> len(pfaff.coordinates("x theta1:65"))
    65
    >>> from sympy.physics.vector import dynamicsymbols
    >>> pfaff.coordinates("x theta") == tuple(dynamicsymbols("x theta"))
    True
    """
    if not isinstance(names, str):
        raise ModelTypeError(f"`names` must be a string such as 'x theta1:4', got {names!r}")
    tokens = [tok for tok in re.split(r"[\s,]+", names) if tok]
    bad = [tok for tok in tokens if not _NAME.fullmatch(tok)]
    if bad or not tokens:
        raise ModelTypeError(
            "`names` must be plain names such as 'x theta1:4' (letters, digits and underscores, "
            f"a range as name1:N), got {names[:80]!r}"
            + (f": {', '.join(repr(b[:40]) for b in bad[:3])} not a name" if bad else "")
        )
    try:
        made = sp.symbols(names, cls=sp.Function)  # as dynamicsymbols(names) does
    except ValueError as e:  # an empty range such as 'x5:3'
        raise ModelTypeError(f"`names`: {names!r} is not a valid range of names ({e})") from None
    if isinstance(made, list | tuple) and not made:
        raise ModelTypeError(f"`names`: {names!r} makes no coordinate (an empty range)")
    return tuple(f(t) for f in made) if isinstance(made, list | tuple) else made(t)


def is_physics_vector(obj: object, kind: str) -> bool:
    """True when ``obj`` is a :mod:`sympy.physics.vector` object of class ``kind`` (``"Vector"``,
    ``"ReferenceFrame"``). Such an object exists only once that package is imported, so pfaff
    never imports it to ask (see the module docstring).

    Examples
    --------
    >>> from sympy.physics.vector import ReferenceFrame
    >>> N = ReferenceFrame("N")
    >>> is_physics_vector(N.x, "Vector"), is_physics_vector(N, "Vector")
    (True, False)
    """
    module = sys.modules.get("sympy.physics.vector")
    return module is not None and isinstance(obj, getattr(module, kind))


def is_coordinate_like(obj: object) -> bool:
    """Return True when ``obj`` is an undefined function applied to :data:`t` alone."""
    return isinstance(obj, AppliedUndef) and obj.args == (t,)


def validate_coordinates(coords: object) -> tuple[sp.Function, ...]:
    """Check coordinates (one, or a sequence), collecting every problem before raising once."""
    if isinstance(coords, str):
        raise ModelTypeError(
            "`coordinates` must be functions of time, not a string: use pfaff.coordinates(names)"
        )
    if isinstance(coords, sp.Basic):
        seq: tuple = (coords,)
    else:
        try:
            seq = tuple(coords)  # type: ignore[arg-type]
        except TypeError:
            raise ModelTypeError(
                f"`coordinates` must be a function of time or a sequence of them, got "
                f"{type(coords).__name__} {coords!r}: make them with pfaff.coordinates('x y')"
            ) from None
    problems = []
    if not seq:
        problems.append("a system needs at least one coordinate")
    for c in seq:
        if not is_coordinate_like(c):
            problems.append(
                f"`{c}` is not a function of time: make coordinates with pfaff.coordinates('x y') "
                "or sympy.physics.vector.dynamicsymbols"
            )
    if len(set(seq)) != len(seq):
        dup = sorted({str(c) for c in seq if seq.count(c) > 1})
        problems.append(f"coordinates listed twice: {', '.join(dup)}")
    if problems:
        raise ModelTypeError("invalid coordinates: " + "; ".join(problems))
    return seq


@cache
def local_q(i: int) -> sp.Symbol:
    """Placeholder for the i-th local coordinate of a template."""
    return sp.Symbol(f"_q{i}")


@cache
def local_qd(i: int) -> sp.Symbol:
    """Placeholder for the i-th local speed of a template."""
    return sp.Symbol(f"_qd{i}")


def as_expr(value: object, what: str) -> sp.Expr:
    """Convert a number or SymPy object to an expression, rejecting anything else and NaN/inf."""
    if isinstance(value, bool) or value is None:
        raise ModelTypeError(f"{what} must be a number or SymPy expression, got {value!r}")
    if isinstance(value, sp.Basic):
        expr = value
    elif isinstance(value, int | float):
        expr = sp.Float(value) if isinstance(value, float) else sp.Integer(value)
    else:
        try:
            import numpy as np

            if isinstance(value, np.integer | np.floating):
                expr = as_expr(value.item(), what)
            else:
                raise TypeError
        except TypeError:
            raise ModelTypeError(
                f"{what} must be a number or SymPy expression, got {type(value).__name__} {value!r}"
            ) from None
    if not isinstance(expr, sp.Expr):
        raise ModelTypeError(f"{what} must be a scalar expression, got {expr!r}")
    if expr.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        raise ModelError(f"{what} contains NaN or infinity: {expr}")
    if expr.has(sp.I):
        raise ModelError(f"{what} must be real, got the complex {expr}")
    reserved = [str(s) for s in expr.free_symbols if _RESERVED.fullmatch(str(s))]
    if reserved:
        raise ModelError(
            f"{what} uses {', '.join(sorted(reserved))}: names of the form _q0, _qd0 (and _fq0, "
            "_fqd0) are pfaff's placeholders; rename the symbol"
        )
    return expr


@cache
def speed(q: sp.Function) -> sp.Derivative:
    """q̇ as ``Derivative(q, t)`` (built directly: ``q.diff(t)`` is 20x slower)."""
    return sp.Derivative(q, t)


@cache
def accel(q: sp.Function) -> sp.Derivative:
    """q̈ as ``Derivative(q, (t, 2))``."""
    return sp.Derivative(q, (t, 2))


def name_clash(symbols: Iterable[sp.Symbol]) -> str | None:
    """The problem when two different symbols share a name (other assumptions), else None.

    A model's parameters are given values by name or by Symbol: with ``Symbol("m",
    positive=True)`` and ``Symbol("m")`` in one model, the name ``"m"`` does not say which.

    Examples
    --------
    >>> name_clash([sp.Symbol("m", positive=True), sp.Symbol("g"), sp.Symbol("m")])
    'two different symbols are both named `m` (assumptions positive=True and none)'
    """
    seen: dict[str, sp.Symbol] = {}
    for s in symbols:
        other = seen.setdefault(s.name, s)
        if other != s:
            first, second = sorted((_given(other), _given(s)), key=lambda a: a == "none")
            return (
                f"two different symbols are both named `{s.name}` (assumptions {first} and "
                f"{second})"
            )
    return None


def _given(s: sp.Symbol) -> str:
    """The assumptions a symbol was created with, as ``key=value`` (``none`` without any)."""
    given = getattr(s, "_assumptions_orig", None)
    if given is None:  # older SymPy: the given ones are assumptions0
        given = s.assumptions0
    given = {k: v for k, v in given.items() if k != "commutative" or v is not True}
    return ", ".join(f"{k}={v}" for k, v in sorted(given.items())) or "none"
